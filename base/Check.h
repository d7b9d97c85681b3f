#pragma once
// Checks for the first two of rhot's three error tiers (the third, bad data from outside, is a
// result the caller must look at):
//
//   RHOT_ASSERT(cond, msg)        a bug in rhot itself.
//   RHOT_PRECONDITION(cond, msg)  a caller broke the contract of a public API.
//
// Both print the condition, the message and the source location to stderr and abort, in every
// build type: a broken invariant in a tracker that drives physics is worse than a crash. Bad data
// from outside (files, packets, images) is the third tier and never reaches these: it is reported
// through a result the caller must inspect.
//
// `msg` is any expression convertible to std::string_view; it is only evaluated on failure.

#include <string_view>

namespace rhot::detail {
[[noreturn]] void check_failed(const char* kind, const char* condition, std::string_view message, const char* file, int line) noexcept;
}  // namespace rhot::detail

#define RHOT_DETAIL_CHECK(kind, cond, msg)                                  \
  do {                                                                      \
    if (!(cond)) [[unlikely]] {                                             \
      ::rhot::detail::check_failed(kind, #cond, (msg), __FILE__, __LINE__); \
    }                                                                       \
  } while (false)

#define RHOT_ASSERT(cond, msg) RHOT_DETAIL_CHECK("assertion", cond, msg)
#define RHOT_PRECONDITION(cond, msg) RHOT_DETAIL_CHECK("precondition", cond, msg)
