#pragma once
// A program started beside this one (rhot-node processes started by rhot-eval nodes and the
// tests): spawned with posix_spawn, its output to a file or inherited, killed when the object
// goes (SIGTERM, then SIGKILL after a grace period), never left behind as a zombie.

#include <expected>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <sys/types.h>

namespace rhot {

class ChildProcess {
 public:
  // argv[0] is the program's path. output: a file for its stdout and stderr (empty: inherited).
  [[nodiscard]] static std::expected<ChildProcess, std::string> spawn(const std::vector<std::string>& argv,
                                                                      const std::filesystem::path& output = {});
  ChildProcess(ChildProcess&& other) noexcept;
  ChildProcess& operator=(ChildProcess&& other) noexcept;
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess();

  pid_t pid() const { return pid_; }
  bool running();
  // SIGKILL now (a crash, a pulled plug), and reaped.
  void kill();
  // SIGTERM, then SIGKILL if it has not ended within grace_s; returns its exit status (or
  // 128 + signal).
  int stop(double grace_s = 2.0);
  // Waits up to timeout_s for it to end by itself: its exit status, or nothing.
  std::optional<int> wait(double timeout_s);

 private:
  explicit ChildProcess(pid_t pid) : pid_(pid) {}
  pid_t pid_ = -1;
  std::optional<int> status_;
};

// The directory of the running program (to find sibling programs such as rhot-node).
std::filesystem::path this_program_dir();

}  // namespace rhot
