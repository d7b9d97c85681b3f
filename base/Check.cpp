#include "base/Check.h"

#include <cstdio>
#include <cstdlib>

namespace rhot::detail {

void check_failed(const char* kind, const char* condition, std::string_view message, const char* file, int line) noexcept {
  std::fprintf(stderr, "rhot: %s failed: %.*s\n  condition: %s\n  at %s:%d\n", kind, static_cast<int>(message.size()), message.data(),
               condition, file, line);
  std::fflush(stderr);
  std::abort();
}

}  // namespace rhot::detail
