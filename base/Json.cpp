#include "base/Json.h"

#include <fstream>
#include <set>
#include <sstream>

namespace rhot {

using nlohmann::json;

std::string json_pointer_token(std::string_view key) {
  std::string out;
  for (const char c : key) {
    if (c == '~') {
      out += "~0";
    } else if (c == '/') {
      out += "~1";
    } else {
      out += c;
    }
  }
  return out;
}

std::string JsonError::to_string() const {
  std::string s = file;
  if (!json_path.empty()) s += (json_path.front() == '/' ? ": " : ":") + json_path;
  return s + ": " + message;
}

std::string describe_json(const json& j) {
  switch (j.type()) {
    case json::value_t::number_float: {
      const double v = j.get<double>();
      if (std::isnan(v)) return "NaN";
      if (std::isinf(v)) return v > 0 ? "infinity" : "-infinity";
      return j.dump();
    }
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::boolean:
    case json::value_t::null:
      return j.dump();
    case json::value_t::string: {
      std::string s = j.dump();
      return s.size() > 40 ? s.substr(0, 37) + "...\"" : s;
    }
    default:
      return std::string("an ") + j.type_name();
  }
}

namespace {

// Rejects duplicate keys, which nlohmann::json would otherwise resolve silently (last one wins),
// reporting the JSON pointer of the repeated key.
class DuplicateKeyCheck {
 public:
  bool operator()(int /*depth*/, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
        frames_.push_back(Frame{false, 0, {}, {}});
        break;
      case json::parse_event_t::array_start:
        frames_.push_back(Frame{true, 0, {}, {}});
        break;
      case json::parse_event_t::key: {
        Frame& f = frames_.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second && !duplicate_) duplicate_ = JsonFailure{path(), "duplicate key \"" + f.key + "\""};
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        frames_.pop_back();
        element_done();
        break;
      case json::parse_event_t::value:
        element_done();
        break;
    }
    return true;
  }
  const std::optional<JsonFailure>& duplicate() const { return duplicate_; }

 private:
  struct Frame {
    bool is_array;
    std::size_t index;
    std::string key;
    std::set<std::string> keys;
  };
  void element_done() {
    if (!frames_.empty() && frames_.back().is_array) ++frames_.back().index;
  }
  std::string path() const {
    std::string p;
    for (const Frame& f : frames_) p += "/" + (f.is_array ? std::to_string(f.index) : json_pointer_token(f.key));
    return p;
  }
  std::vector<Frame> frames_;
  std::optional<JsonFailure> duplicate_;
};

std::string line_and_column(std::string_view text, std::size_t byte) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i + 1 < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return std::to_string(line) + ":" + std::to_string(column);
}

}  // namespace

std::expected<nlohmann::json, JsonError> parse_json_text(std::string_view json_text, std::string_view name) {
  const std::string file(name);
  DuplicateKeyCheck duplicates;
  json root;
  try {
    root = json::parse(json_text.begin(), json_text.end(), std::ref(duplicates));
  } catch (const json::parse_error& e) {
    // nlohmann's message starts "[json.exception.parse_error.101] parse error at line 1, column 2: ";
    // keep only the part after the position, which we give in the file:line:col form ourselves.
    std::string what = e.what();
    if (const auto colon = what.find(": "); colon != std::string::npos) what = what.substr(colon + 2);
    return std::unexpected(JsonError{file, line_and_column(json_text, e.byte), "invalid JSON: " + what});
  } catch (const json::out_of_range& e) {
    // A number too large for a double, such as 1e999: nlohmann gives the token but no position,
    // so find the token in the text. Such a number would be infinity, which must never reach
    // physics or rendering.
    const std::string what = e.what();
    const auto open = what.find('\'');
    const auto close = what.rfind('\'');
    std::string where;
    if (open != std::string::npos && close > open) {
      const std::string token = what.substr(open + 1, close - open - 1);
      if (const auto at = json_text.find(token); at != std::string_view::npos) where = line_and_column(json_text, at + 1);
      return std::unexpected(JsonError{file, where, "invalid JSON: the number " + token + " is out of range"});
    }
    return std::unexpected(JsonError{file, where, "invalid JSON: " + what});
  }
  if (duplicates.duplicate()) {
    return std::unexpected(JsonError{file, duplicates.duplicate()->json_path, duplicates.duplicate()->message});
  }
  return root;
}

std::expected<std::string, JsonError> read_text_file(const std::filesystem::path& file, std::string_view what) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    return std::unexpected(JsonError{file.string(), "", std::string(what) + " file not found"});
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in && !in.eof()) return std::unexpected(JsonError{file.string(), "", "cannot read the file"});
  return text.str();
}

}  // namespace rhot
