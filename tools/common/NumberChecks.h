#pragma once

// Checks for numeric command-line options that say in words what is wrong with the text, where
// CLI11's own (CLI::PositiveNumber and friends) quote a range up to 1.8e308 and let a number too
// large for a double through to a conversion that throws.
//
//   app.add_option("--sigma", sigma, "...")->check(rhot::number_check(rhot::NumberBound::kPositive));
//
// The whole text must be one finite number (std::from_chars: no sign "+", no spaces, "nan" and
// "inf" refused), then above 0 or at least 0 where the bound says so.

#include <charconv>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

#include <CLI/CLI.hpp>

namespace rhot {

enum class NumberBound { kAny, kPositive, kNonNegative };

// The text as one finite number (the rules above), or nothing.
inline std::optional<double> finite_number(std::string_view text) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

inline CLI::Validator number_check(NumberBound bound) {
  return CLI::Validator(
      [bound](std::string& text) -> std::string {
        double v = 0.0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (ec == std::errc::result_out_of_range || (ec == std::errc() && !std::isfinite(v)))
          return "expected a finite number, got " + text;
        if (ec != std::errc() || end != text.data() + text.size()) return "expected a number, got " + text;
        if (bound == NumberBound::kPositive && !(v > 0.0)) return "expected a number above 0, got " + text;
        if (bound == NumberBound::kNonNegative && !(v >= 0.0)) return "expected 0 or more, got " + text;
        return {};
      },
      bound == NumberBound::kPositive      ? "POSITIVE"
      : bound == NumberBound::kNonNegative ? "NONNEGATIVE"
                                           : "");
}

}  // namespace rhot
