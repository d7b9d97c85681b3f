#include "tracking/rigid/StarSet.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "tracking/rigid/StarGenerator.h"

namespace rhot {
namespace {

namespace fs = std::filesystem;

fs::path temp(const std::string& name) {
  const fs::path d = fs::path(::testing::TempDir()) / "rhot_star_set_test";
  fs::create_directories(d);
  return d / name;
}

StarSet generate(double diameter, Eigen::Vector3d box, double variation, int candidates = 20000, unsigned seed = 1) {
  StarGeneratorSettings s;
  s.rules = {diameter, box, variation};
  s.candidates = candidates;
  s.seed = seed;
  auto set = generate_star_set(s);
  EXPECT_TRUE(set.has_value()) << (set ? "" : set.error());
  return set.value_or(StarSet{});
}

// A valid one-star set written by hand.
StarSet hand_made() {
  StarSet set;
  set.rules = {4.0, {20.8, 12.6, 48.3}, 1.5};
  set.stars.push_back({0,
                       {Eigen::Vector3d(-7.0, -3.0, 2.0), Eigen::Vector3d(7.5, 2.0, 9.0), Eigen::Vector3d(-2.0, 3.5, 20.0),
                        Eigen::Vector3d(4.0, -2.5, 40.0)}});
  return set;
}

TEST(StarSet, TheSeedCaseGivesFarMoreThanTheSeedsTwentyFiveValidStars) {
  const StarSet set = generate(4.0, {20.8, 12.6, 48.3}, 1.5);
  EXPECT_GE(set.stars.size(), 40u);
  const auto problems = check_star_set(set);
  EXPECT_TRUE(problems.empty()) << problems.front();
}

TEST(StarSet, OtherBoxesDiametersAndVariationsAreValidToo) {
  struct Case {
    double diameter;
    Eigen::Vector3d box;
    double variation;
  };
  for (const Case& c :
       {Case{3.0, {15, 15, 30}, 1.0}, Case{6.0, {30, 20, 60}, 2.0}, Case{4.0, {25, 25, 25}, 3.0}, Case{10.0, {80, 40, 120}, 5.0}}) {
    const StarSet set = generate(c.diameter, c.box, c.variation, 2000, 7);
    EXPECT_GE(set.stars.size(), 1u) << c.diameter << " mm in " << c.box.transpose();
    const auto problems = check_star_set(set);
    EXPECT_TRUE(problems.empty()) << c.diameter << " mm in " << c.box.transpose() << ": " << problems.front();
  }
}

TEST(StarSet, GenerationIsDeterministicForASeed) {
  const StarSet a = generate(4.0, {20.8, 12.6, 48.3}, 1.5, 3000, 5);
  const StarSet b = generate(4.0, {20.8, 12.6, 48.3}, 1.5, 3000, 5);
  ASSERT_EQ(a.stars.size(), b.stars.size());
  for (std::size_t i = 0; i < a.stars.size(); ++i) EXPECT_EQ(a.stars[i].markers_mm, b.stars[i].markers_mm);
}

TEST(StarSet, BadGeneratorArgumentsAreRefused) {
  StarGeneratorSettings s;
  s.rules.marker_diameter_mm = -4.0;
  EXPECT_EQ(generate_star_set(s).error(), "marker diameter: must be a positive number of millimetres, got -4");
  s.rules = {4.0, {20.8, 0.0, 48.3}, 1.5};
  EXPECT_EQ(generate_star_set(s).error(), "box: every side must be a positive number of millimetres, got 20.8 x 0 x 48.3");
  s.rules = {4.0, {20.8, 12.6, 48.3}, std::nan("")};
  EXPECT_EQ(generate_star_set(s).error(), "variation: must be a positive number of millimetres, got nan");
  s.rules = {4.0, {9, 9, 9}, 1.5};
  EXPECT_EQ(generate_star_set(s).error(), "box 9 x 9 x 9 mm is too small for one star of 4 mm markers with edges 1.5 mm apart");
  s.rules = {4.0, {12, 12, 12}, 1.5};
  s.candidates = 100;
  EXPECT_EQ(generate_star_set(s).error(), "box 12 x 12 x 12 mm is too small for one star of 4 mm markers with edges 1.5 mm apart");
}

TEST(StarSet, TheCheckerFindsEveryBrokenRule) {
  StarSet set = hand_made();
  ASSERT_TRUE(check_star_set(set).empty()) << check_star_set(set).front();

  StarSet overlap = set;
  overlap.stars[0].markers_mm[1] = overlap.stars[0].markers_mm[0] + Eigen::Vector3d(3.0, 0.0, 0.0);
  EXPECT_EQ(check_star_set(overlap).front(), "stars[0] (id 0): markers 0 and 1 overlap (3 mm apart)");

  StarSet outside = set;
  outside.stars[0].markers_mm[3].z() = 47.0;  // its sphere reaches 49 mm
  EXPECT_EQ(check_star_set(outside).back(), "stars[0] (id 0): marker 3 is not inside the box");

  // Two equal edges: an isosceles face.
  StarSet iso;
  iso.rules = set.rules;
  iso.stars.push_back({0, {Eigen::Vector3d(-6, 0, 2), Eigen::Vector3d(6, 0, 2), Eigen::Vector3d(0, 0, 30), Eigen::Vector3d(0, 4, 12)}});
  EXPECT_NE(std::find(check_star_set(iso).begin(), check_star_set(iso).end(),
                      "stars[0] (id 0): edges 28.64 and 28.64 mm differ by less than 1.5 mm"),
            check_star_set(iso).end());

  // The mirror image of a star has the same faces: refused, as is a rotated copy.
  StarSet mirrored = set;
  MarkerStar m = set.stars[0];
  m.id = 1;
  for (Eigen::Vector3d& p : m.markers_mm) p.x() = -p.x();
  mirrored.stars.push_back(m);
  const auto problems = check_star_set(mirrored);
  ASSERT_EQ(problems.size(), 4u) << "each face matches its mirror";
  EXPECT_EQ(problems[0], "stars[0] (id 0) face 0 and stars[1] (id 1) face 0 differ by at most 0 mm in every edge");

  StarSet twice = set;
  twice.stars.push_back(set.stars[0]);
  EXPECT_EQ(check_star_set(twice).front(), "stars[1] (id 0): duplicate id");
}

TEST(StarSet, SaveThenLoadIsExact) {
  const StarSet set = generate(4.0, {20.8, 12.6, 48.3}, 1.5, 2000);
  ASSERT_FALSE(set.stars.empty());
  const fs::path file = temp("set.json");
  ASSERT_TRUE(save_star_set(set, file).has_value());
  const auto back = load_star_set(file);
  ASSERT_TRUE(back.has_value()) << back.error();
  EXPECT_EQ(back->rules.box_mm, set.rules.box_mm);
  ASSERT_EQ(back->stars.size(), set.stars.size());
  for (std::size_t i = 0; i < set.stars.size(); ++i) {
    EXPECT_EQ(back->stars[i].id, set.stars[i].id);
    EXPECT_EQ(back->stars[i].markers_mm, set.stars[i].markers_mm);
  }
}

std::string load_error(const std::string& text) {
  const fs::path file = temp("bad.json");
  std::ofstream(file) << text;
  const auto r = load_star_set(file);
  if (r) return "loaded";
  // "FILE: /pointer: message", or "FILE:line:col: message" for syntax errors.
  std::string e = r.error().substr(file.string().size());
  return e.substr(e.rfind(": ", 0) == 0 ? 2 : 1);
}

TEST(StarSet, MalformedFilesAreRefusedWithWhatIsWrong) {
  EXPECT_EQ(load_star_set(temp("none.json")).error(), temp("none.json").string() + ": star set file not found");
  const std::string head =
      R"("format": "rhot-marker-stars", "version": 1, "marker_diameter_mm": 4, "box_mm": [20.8, 12.6, 48.3], "variation_mm": 1.5)";
  EXPECT_EQ(load_error("{" + head + R"(, "stars": []})"), "loaded");
  EXPECT_EQ(load_error(R"({"format": "mocap"})"), "/format: expected \"rhot-marker-stars\", got \"mocap\"");
  EXPECT_EQ(load_error(R"({"format": "rhot-marker-stars", "version": 2})"), "/version: expected an integer from 1 to 1, got 2");
  EXPECT_EQ(load_error("{" + head + "}"), "/: missing required key \"stars\"");
  EXPECT_EQ(load_error("{" + head + R"(, "stars": [{"id": 0, "markers_mm": [[0, 0, 2], [9, 0, 2], [0, 9, 2]]}]})"),
            "/stars/0/markers_mm: expected four [x, y, z] marker centres, got an array");
  EXPECT_EQ(load_error("{" + head + R"(, "stars": [{"id": 0, "markers_mm": [[0, 0, 2], [9, 0, 2], [0, 9, 2], [0, "x", 2]]}]})"),
            "/stars/0/markers_mm/3/1: expected a number, got \"x\"");
  EXPECT_EQ(load_error("{" + head + R"(, "stars": [{"id": "a", "markers_mm": []}]})"), "/stars/0/id: expected an integer, got \"a\"");
  EXPECT_EQ(
      load_error(
          R"({"format": "rhot-marker-stars", "version": 1, "marker_diameter_mm": 0, "box_mm": [1, 1, 1], "variation_mm": 1, "stars": []})"),
      "/marker_diameter_mm: expected a number greater than 0 (and within float range), got 0");
  // A set that breaks a rule: the first problem, and how many more.
  EXPECT_EQ(load_error("{" + head + R"(, "stars": [{"id": 0, "markers_mm": [[0, 0, 2], [1, 0, 2], [0, 5, 20], [0, -5, 40]]}]})"),
            "stars[0] (id 0): markers 0 and 1 overlap (1 mm apart) (and 5 more)");
  EXPECT_NE(load_error("{ not json"), "loaded");
}

}  // namespace
}  // namespace rhot
