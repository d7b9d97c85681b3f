#pragma once
// Runs one of rhot's real programs through the shell and collects what it prints and how it ends.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace rhot::test {

struct CommandRun {
  int exit_code = -1;  // -1: did not exit normally
  std::string output;
};

// `program` is a file name in the build folder; `redirect` e.g. "2>&1" (both streams) or
// "2>/dev/null" (stdout only); `env_prefix` e.g. "env -u DISPLAY".
inline CommandRun run_program(const std::string& program, const std::string& args, const std::string& redirect,
                              const std::string& env_prefix = "") {
  const std::string command = env_prefix + " " + std::string(RHOT_BINARY_DIR) + "/" + program + " " + args + " " + redirect;
  CommandRun r;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buffer{};
  while (fgets(buffer.data(), static_cast<int>(buffer.size()), pipe) != nullptr) r.output += buffer.data();
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace rhot::test
