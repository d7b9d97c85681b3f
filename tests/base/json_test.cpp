// The one JSON reader every loader uses: each failure names the file, where in it, and what was
// expected.

#include "base/Json.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

namespace rhot {
namespace {

struct Point {
  double x = 0.0;
  int n = 0;
  std::string name;
};

Point read_point(const JsonNode& j) {
  j.expect_object({"x", "n", "name"});
  Point p;
  p.x = j["x"].number();
  if (auto n = j.optional("n")) p.n = n->integer_in(0, 10);
  if (auto name = j.optional("name")) p.name = name->non_empty_string();
  return p;
}

std::string error_of(std::string_view text) {
  const auto r = parse_json<Point>(text, "p.json", read_point);
  return r ? "parsed" : r.error().to_string();
}

TEST(Json, AGoodDocumentIsRead) {
  const auto p = parse_json<Point>(R"({"x": 1.5, "n": 3, "name": "a"})", "p.json", read_point);
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->x, 1.5);
  EXPECT_EQ(p->n, 3);
  EXPECT_EQ(p->name, "a");
}

TEST(Json, EveryFailureNamesTheFileThePointerAndWhatWasExpected) {
  EXPECT_EQ(error_of(R"({"n": 3})"), "p.json: /: missing required key \"x\"");
  EXPECT_EQ(error_of(R"({"x": "far"})"), "p.json: /x: expected a number, got \"far\"");
  EXPECT_EQ(error_of(R"({"x": 1, "n": 11})"), "p.json: /n: expected an integer from 0 to 10, got 11");
  EXPECT_EQ(error_of(R"({"x": 1, "n": 2.5})"), "p.json: /n: expected an integer, got 2.5");
  EXPECT_EQ(error_of(R"({"x": 1, "name": ""})"), "p.json: /name: expected a non-empty string");
  EXPECT_EQ(error_of(R"({"x": 1, "colour": 2})"), "p.json: /colour: unknown key \"colour\"; expected one of: x, n, name");
  EXPECT_EQ(error_of(R"([1, 2])"), "p.json: /: expected an object, got an array");
  // Keys are spelled as JSON pointers spell them (RFC 6901).
  EXPECT_EQ(error_of(R"({"x": 1, "a/b~c": 2})"), "p.json: /a~1b~0c: unknown key \"a/b~c\"; expected one of: x, n, name");
}

TEST(Json, SyntaxDuplicatesAndNumbersNoDoubleHoldsAreRefused) {
  EXPECT_EQ(error_of("{\"x\": 1,\n \"n\": }"),
            "p.json:2:7: invalid JSON: syntax error while parsing value - unexpected '}'; expected '[', '{', or a literal");
  EXPECT_EQ(error_of(R"({"x": 1, "x": 2})"), "p.json: /x: duplicate key \"x\"");
  EXPECT_EQ(error_of(R"({"x": 1e999})"), "p.json:1:7: invalid JSON: the number 1e999 is out of range");
  EXPECT_EQ(error_of(R"({"x": 1e39})"), "p.json: /x: expected a number within float range (magnitude up to 3.4e38), got 1e+39");
}

TEST(Json, FilesThatAreMissingAreNamed) {
  const auto missing = read_json_file<Point>("/nonexistent/p.json", "point", read_point);
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error().to_string(), "/nonexistent/p.json: point file not found");
  const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) / "rhot_json_test.json";
  std::ofstream(file) << R"({"x": 2})";
  const auto read = read_json_file<Point>(file, "point", read_point);
  ASSERT_TRUE(read.has_value()) << read.error().to_string();
  EXPECT_EQ(read->x, 2.0);
}

TEST(Json, ValuesAreDescribedAsAPersonWouldWriteThem) {
  EXPECT_EQ(describe_json(nlohmann::json(std::nan(""))), "NaN");
  EXPECT_EQ(describe_json(nlohmann::json(-INFINITY)), "-infinity");
  EXPECT_EQ(describe_json(nlohmann::json(std::string(60, 'a'))), "\"" + std::string(36, 'a') + "...\"");
  EXPECT_EQ(describe_json(nlohmann::json::object()), "an object");
}

}  // namespace
}  // namespace rhot
