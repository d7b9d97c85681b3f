#pragma once
// What a loader of a JSON file reports (base/Json.h reads the files): the file, where in it, and
// what was wrong. Light to include: no JSON library behind it.

#include <string>

namespace rhot {

struct JsonError {
  std::string file;       // the file (or the name given to parse_json)
  std::string json_path;  // JSON pointer; empty for errors about the whole file; "line:col" for syntax
  std::string message;    // what was wrong and what was expected

  // "file: /json/path: message" ("file:line:col: message" for syntax)
  std::string to_string() const;
};

}  // namespace rhot
