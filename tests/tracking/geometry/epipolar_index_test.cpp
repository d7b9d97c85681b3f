#include "tracking/geometry/EpipolarIndex.h"

#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

namespace rhot {
namespace {

// The points within the tolerance of a line, by testing every one. In scalars, in the order of
// Eigen's line.dot(point.homogeneous()): this test program is compiled at -O0 under the
// sanitizers, where each of Eigen's expression functions is a call and the 3.7 million products
// took most of the test's 12 s.
std::vector<int> brute_force(std::span<const Eigen::Vector2d> points, std::span<const char> skip, const Eigen::Vector3d& line,
                             double tolerance) {
  std::vector<int> out;
  const double a = line.x(), b = line.y(), c = line.z();
  for (std::size_t k = 0; k < points.size(); ++k) {
    const double* p = points[k].data();
    if (skip[k] == 0 && std::abs(a * p[0] + b * p[1] + c) <= tolerance) out.push_back(static_cast<int>(k));
  }
  return out;
}

// For epipoles inside the image, outside it, at infinity and on the optical axis, and points
// spread over the image and crowded at the epipole: every query finds exactly the points a full
// scan finds, in the same order.
TEST(EpipolarIndex, FindsExactlyThePointsAScanFinds) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> image(-0.7, 0.7);
  std::normal_distribution<double> jitter(0.0, 0.004);
  const std::vector<Eigen::Vector3d> epipoles = {{0.1, -0.2, 1.0},    // inside the image
                                                 {3.0, 1.0, 1.0},     // outside it
                                                 {1.0, 0.5, 0.0},     // at infinity (cameras side by side)
                                                 {0.0, 0.0, 1.0},     // the image centre (cameras one behind the other)
                                                 {0.2, 0.1, -1.0},    // behind the camera
                                                 {1.0, 0.0, 1e-12}};  // all but at infinity
  int compared = 0;
  int found = 0;
  for (const Eigen::Vector3d& e : epipoles) {
    std::vector<Eigen::Vector2d> points;
    for (int k = 0; k < 2000; ++k) points.push_back(Eigen::Vector2d{image(rng), image(rng)});
    if (std::abs(e.z()) > 1e-6) {
      for (int k = 0; k < 50; ++k) points.push_back(Eigen::Vector2d{e.x() / e.z() + jitter(rng), e.y() / e.z() + jitter(rng)});
    }
    std::vector<char> skip(points.size(), 0);
    for (std::size_t k = 0; k < skip.size(); k += 5) skip[k] = 1;
    EpipolarIndex index;
    index.build(e, points, skip);
    EXPECT_EQ(index.size(), points.size() - (points.size() + 4) / 5);
    std::vector<int> got;
    for (int q = 0; q < 300; ++q) {
      // A line through the epipole and a random point; tolerances from 0.1 to 10 pixels at f = 800.
      const Eigen::Vector3d through = Eigen::Vector2d{image(rng), image(rng)}.homogeneous();
      Eigen::Vector3d line = e.cross(through);
      line *= std::exp(image(rng) * 5.0);  // any scale
      const double tolerance =
          line.head<2>().norm() * std::exp(std::uniform_real_distribution<double>(std::log(0.1), std::log(10.0))(rng)) / 800.0;
      index.query(line, tolerance, got);
      const std::vector<int> want = brute_force(points, skip, line, tolerance);
      EXPECT_EQ(got, want) << "epipole " << e.transpose() << " query " << q;
      ++compared;
      found += static_cast<int>(want.size());
    }
  }
  EXPECT_EQ(compared, 6 * 300);
  EXPECT_GT(found, 6 * 300);  // the queries found points, so the comparison meant something
}

TEST(EpipolarIndex, AnEmptyIndexFindsNothing) {
  EpipolarIndex index;
  index.build({0, 0, 1}, {}, {});
  std::vector<int> got = {3};
  index.query({1, 0, 0}, 1.0, got);
  EXPECT_TRUE(got.empty());
}

}  // namespace
}  // namespace rhot
