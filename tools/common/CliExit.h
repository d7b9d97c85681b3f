#pragma once

// The exit status of a command-line tool whose flags CLI11 could not parse. CLI11's own
// `return app.exit(e)` (and its CLI11_PARSE macro) exits with codes such as 105 or 106, one per kind
// of mistake; rhot's tools promise exit status 1 for any bad flag (docs/calibration.md).
//
//   try {
//     app.parse(argc, argv);
//   } catch (const CLI::ParseError& e) {
//     return rhot::cli_exit_status(app, e);
//   }
//
// --help, --help-all and --version print to stdout and give 0. Any other parse error prints CLI11's
// message to stderr and gives 1, except a CLI::RuntimeError, which a callback throws on purpose to
// choose the exit status itself: that status is kept.

#include <CLI/CLI.hpp>

namespace rhot {

inline int cli_exit_status(const CLI::App& app, const CLI::ParseError& e) {
  const int cli11_status = app.exit(e);                            // prints the help, the version or the error message
  if (dynamic_cast<const CLI::Success*>(&e) != nullptr) return 0;  // also CallForHelp, CallForAllHelp, CallForVersion
  if (dynamic_cast<const CLI::RuntimeError*>(&e) != nullptr) return cli11_status;
  return 1;
}

}  // namespace rhot
