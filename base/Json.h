#pragma once
// Reading JSON files the one way every loader of rhot does (scenes, hand layouts, star sets, hand
// calibrations, recordings): a JsonNode is a value and its JSON pointer, whose typed accessors
// fail naming that pointer and what was expected, and read_json_file / parse_json turn any failure
// into a JsonError: "<file>: <where>: <what was wrong and what was expected>".
//
// Refused besides wrong types: syntax errors (where: "line:column"), duplicate keys (which
// nlohmann::json would resolve silently, last one wins), numbers out of a double's range, NaN and
// infinities where a number is expected.

#include <cmath>
#include <expected>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/JsonError.h"

namespace rhot {

// Thrown by JsonNode::fail; parse_json catches it. Loaders never let it escape.
struct JsonFailure {
  std::string json_path;
  std::string message;
};

// A key as a JSON pointer spells it (RFC 6901): "~" as "~0", "/" as "~1".
std::string json_pointer_token(std::string_view key);

// A value as a message quotes it: numbers as written (NaN, infinity spelled out), strings quoted
// and cut at 40 characters, "an object" or "an array".
std::string describe_json(const nlohmann::json& j);

// A JSON value and where it is, with typed accessors that fail (throw JsonFailure) naming the path.
class JsonNode {
 public:
  JsonNode(const nlohmann::json& value, std::string path) : j_(value), path_(std::move(path)) {}
  JsonNode(nlohmann::json&&, std::string) = delete;  // it keeps a reference: the value must outlive it

  const std::string& path() const { return path_; }
  const nlohmann::json& raw() const { return j_; }

  [[noreturn]] void fail(const std::string& message) const { throw JsonFailure{path_, message}; }

  // Checks that this is an object whose keys are all among `allowed`.
  void expect_object(std::initializer_list<std::string_view> allowed) const {
    if (!j_.is_object()) fail("expected an object, got " + describe_json(j_));
    for (const auto& [key, value] : j_.items()) {
      bool known = false;
      for (const std::string_view a : allowed) known = known || a == key;
      if (!known) {
        std::string list;
        for (const std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        JsonNode(value, path_ + "/" + json_pointer_token(key)).fail("unknown key \"" + key + "\"; expected one of: " + list);
      }
    }
  }

  bool has(const char* key) const { return j_.contains(key); }
  JsonNode operator[](const char* key) const {
    if (!j_.contains(key)) fail(std::string("missing required key \"") + key + "\"");
    return JsonNode(j_.at(key), path_ + "/" + json_pointer_token(key));
  }
  std::optional<JsonNode> optional(const char* key) const {
    if (!j_.contains(key)) return std::nullopt;
    return JsonNode(j_.at(key), path_ + "/" + json_pointer_token(key));
  }
  std::vector<JsonNode> elements() const {
    if (!j_.is_array()) fail("expected an array, got " + describe_json(j_));
    std::vector<JsonNode> out;
    for (std::size_t i = 0; i < j_.size(); ++i) out.emplace_back(j_[i], path_ + "/" + std::to_string(i));
    return out;
  }

  double number() const {
    if (!j_.is_number()) fail("expected a number, got " + describe_json(j_));
    const double v = j_.get<double>();
    if (!std::isfinite(v)) fail("expected a finite number, got " + describe_json(j_));
    if (std::abs(v) > static_cast<double>(std::numeric_limits<float>::max())) {
      fail("expected a number within float range (magnitude up to 3.4e38), got " + describe_json(j_));
    }
    return v;
  }
  double number_in(double lo, double hi, const char* what) const {
    const double v = number();
    if (v < lo || v > hi) fail(std::string("expected ") + what + ", got " + describe_json(j_));
    return v;
  }
  double positive() const {
    const double v = number();
    // Stored as float downstream: refuse what a float turns into 0 or infinity.
    if (!(v > 0.0) || !(static_cast<float>(v) > 0.0f) || v > static_cast<double>(std::numeric_limits<float>::max())) {
      fail("expected a number greater than 0 (and within float range), got " + describe_json(j_));
    }
    return v;
  }
  int integer_in(int lo, int hi) const {
    if (!j_.is_number_integer() && !j_.is_number_unsigned()) fail("expected an integer, got " + describe_json(j_));
    const auto v = j_.get<long long>();
    if (v < lo || v > hi) {
      fail("expected an integer from " + std::to_string(lo) + " to " + std::to_string(hi) + ", got " + describe_json(j_));
    }
    return static_cast<int>(v);
  }
  bool boolean() const {
    if (!j_.is_boolean()) fail("expected true or false, got " + describe_json(j_));
    return j_.get<bool>();
  }
  std::string string() const {
    if (!j_.is_string()) fail("expected a string, got " + describe_json(j_));
    return j_.get<std::string>();
  }
  std::string non_empty_string() const {
    std::string s = string();
    if (s.empty()) fail("expected a non-empty string");
    return s;
  }
  // An array of exactly n finite numbers.
  std::vector<double> numbers(std::size_t n) const {
    if (!j_.is_array() || j_.size() != n) {
      fail("expected an array of " + std::to_string(n) + " numbers, got " + describe_json(j_) +
           (j_.is_array() ? " of " + std::to_string(j_.size()) : ""));
    }
    std::vector<double> out;
    for (const JsonNode& e : elements()) out.push_back(e.number());
    return out;
  }

 private:
  const nlohmann::json& j_;
  std::string path_;
};

// Parses `text` (duplicate keys refused), then runs `read` on the root. `file` names the text in
// errors.
[[nodiscard]] std::expected<nlohmann::json, JsonError> parse_json_text(std::string_view text, std::string_view file);

template <typename T>
[[nodiscard]] std::expected<T, JsonError> parse_json(std::string_view text, std::string_view file,
                                                     const std::function<T(const JsonNode&)>& read) {
  auto root = parse_json_text(text, file);
  if (!root) return std::unexpected(root.error());
  try {
    return read(JsonNode(*root, ""));
  } catch (const JsonFailure& f) {
    return std::unexpected(JsonError{std::string(file), f.json_path.empty() ? "/" : f.json_path, f.message});
  }
}

// The whole file as text. Errors (json_path empty): "<what> file not found", "cannot read the file".
[[nodiscard]] std::expected<std::string, JsonError> read_text_file(const std::filesystem::path& file, std::string_view what);

// read_text_file, then parse_json.
template <typename T>
[[nodiscard]] std::expected<T, JsonError> read_json_file(const std::filesystem::path& file, std::string_view what,
                                                         const std::function<T(const JsonNode&)>& read) {
  auto text = read_text_file(file, what);
  if (!text) return std::unexpected(text.error());
  return parse_json<T>(*text, file.string(), read);
}

}  // namespace rhot
