// The rig's registration to a headset (tracking/calib/HeadsetRegistration.h) from a star on the
// headset and the head's poses, against known transforms.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "tracking/calib/HeadsetRegistration.h"

namespace rhot {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

Rigid3d pose(const Eigen::Vector3d& rotation_vector, const Eigen::Vector3d& t) {
  Rigid3d r;
  const double a = rotation_vector.norm();
  r.rotation = a > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(a, rotation_vector / a)) : Eigen::Quaterniond::Identity();
  r.translation = t;
  return r;
}

const Rigid3d kWorldFromStage = pose(Eigen::Vector3d(0.02, 0.6, -0.01), Eigen::Vector3d(0.35, -0.42, -0.28));
const Rigid3d kHeadFromStar = pose(Eigen::Vector3d(-0.3, 0.05, 0.1), Eigen::Vector3d(0.01, 0.09, 0.03));

// A seated user looking around for `seconds` at 20 Hz: yaw `yaw_deg`, pitch and roll `tilt_deg`,
// the head wandering a few centimetres; the star's tracked pose with noise (`noise_mm`, and a
// tenth of a degree per millimetre) and, every `outlier_every`-th sample, 10 cm off.
std::vector<HeadsetPoseSample> look_around(double seconds, double yaw_deg, double tilt_deg, double noise_mm, int outlier_every,
                                           unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<HeadsetPoseSample> out;
  for (int i = 0; i < static_cast<int>(seconds * 20.0); ++i) {
    const double t = i / 20.0;
    HeadsetPoseSample s;
    s.t_s = t;
    const Eigen::Vector3d turn(tilt_deg * kDeg * std::sin(0.71 * t), yaw_deg * kDeg * std::sin(0.43 * t + 1.0),
                               tilt_deg * kDeg * 0.5 * std::sin(0.97 * t));
    s.stage_from_head = pose(turn, Eigen::Vector3d(0.04 * std::sin(0.3 * t), 1.6 + 0.02 * std::sin(0.5 * t), 0.03 * std::cos(0.37 * t)));
    Rigid3d star = kWorldFromStage * s.stage_from_head * kHeadFromStar;
    const Eigen::Vector3d dt = 1e-3 * noise_mm * Eigen::Vector3d{n(rng), n(rng), n(rng)};
    const Eigen::Vector3d dr = 0.1 * kDeg * noise_mm * Eigen::Vector3d{n(rng), n(rng), n(rng)};
    star = star * pose(dr, Eigen::Vector3d::Zero());  // turned about its own origin
    star.translation += dt;
    if (outlier_every > 0 && i % outlier_every == outlier_every - 1) star.translation += Eigen::Vector3d(0.1, 0.0, 0.0);
    s.world_from_star = star;
    out.push_back(s);
  }
  return out;
}

double angle_deg(const Rigid3d& a, const Rigid3d& b) { return a.rotation.angularDistance(b.rotation) / kDeg; }
double distance_mm(const Rigid3d& a, const Rigid3d& b) { return 1e3 * (a.translation - b.translation).norm(); }
// Where the registration puts the head's usual place (1.6 m above the stage's origin), against
// the truth: the error that matters where the user is. The stage's origin itself is 1.6 m from
// every sample, so a rotation error of 0.02 degrees already moves it by half a millimetre.
double at_head_mm(const Rigid3d& world_from_stage) {
  const Eigen::Vector3d head(0.0, 1.6, 0.0);
  return 1e3 * (world_from_stage * head - kWorldFromStage * head).norm();
}

TEST(HeadsetRegistration, RecoversTheStageAndTheStarsPlaceOnTheHeadsetFromThirtySecondsOfLookingAround) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    const auto samples = look_around(30.0, 40.0, 15.0, 0.5, 0, seed);
    const auto r = register_headset(samples);
    ASSERT_TRUE(r.has_value()) << r.error();
    EXPECT_LT(angle_deg(r->world_from_stage, kWorldFromStage), 0.05) << "seed " << seed;
    EXPECT_LT(distance_mm(r->world_from_stage, kWorldFromStage), 2.0) << "seed " << seed;
    EXPECT_LT(at_head_mm(r->world_from_stage), 0.2) << "seed " << seed;
    EXPECT_LT(angle_deg(r->head_from_star, kHeadFromStar), 0.05) << "seed " << seed;
    EXPECT_LT(distance_mm(r->head_from_star, kHeadFromStar), 0.5) << "seed " << seed;
    // The residuals are the noise: 0.5 mm per axis is 0.87 mm in 3-D.
    EXPECT_NEAR(r->rms_mm, 0.87, 0.15) << "seed " << seed;
    EXPECT_EQ(r->samples, samples.size());
    EXPECT_NEAR(r->turn_deg, 80.0, 15.0);
  }
}

TEST(HeadsetRegistration, AStarMisreadNowAndThenDoesNotMoveIt) {
  const auto samples = look_around(30.0, 40.0, 15.0, 0.5, 20, 4);  // 5 % of the samples 10 cm off
  const auto r = register_headset(samples);
  ASSERT_TRUE(r.has_value()) << r.error();
  EXPECT_LT(angle_deg(r->world_from_stage, kWorldFromStage), 0.1);
  EXPECT_LT(distance_mm(r->world_from_stage, kWorldFromStage), 2.0);
  // Plain least squares would move it by about the outliers' mean, 5 mm (measured: 0.34 mm).
  EXPECT_LT(at_head_mm(r->world_from_stage), 0.5);
}

TEST(HeadsetRegistration, AMotionThatCannotTellTheTransformsApartIsRefusedSayingWhatItLacked) {
  const auto one_axis = look_around(30.0, 40.0, 0.0, 0.5, 0, 5);
  const auto r1 = register_headset(one_axis);
  ASSERT_FALSE(r1.has_value());
  EXPECT_EQ(r1.error(),
            "the head turned about one axis only: its offset along that axis cannot be told from the registration; nod and tilt it too");
  const auto still = look_around(30.0, 0.5, 0.2, 0.0, 0, 6);
  const auto r2 = register_headset(still);
  ASSERT_FALSE(r2.has_value());
  EXPECT_NE(r2.error().find("the head turned at most"), std::string::npos) << r2.error();
  const auto few = look_around(1.0, 40.0, 15.0, 0.5, 0, 7);
  const auto r3 = register_headset(few);
  ASSERT_FALSE(r3.has_value());
  EXPECT_EQ(r3.error(), "only 20 samples of the headset's star and head; at least 30 are needed");
  auto bad = look_around(30.0, 40.0, 15.0, 0.5, 0, 8);
  bad[7].stage_from_head.translation.x() = std::nan("");
  const auto r4 = register_headset(bad);
  ASSERT_FALSE(r4.has_value());
  EXPECT_EQ(r4.error(), "sample 7 is not finite");
}

TEST(HeadsetRegistration, TheFileReadsBackAndAFileThatIsNotARegistrationIsRefusedNamingTheEntry) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "rhot_headset_registration";
  std::filesystem::create_directories(dir);
  const auto r = register_headset(look_around(30.0, 40.0, 15.0, 0.5, 0, 9));
  ASSERT_TRUE(r.has_value()) << r.error();
  const std::filesystem::path file = dir / "headset.yaml";
  ASSERT_TRUE(write_headset_registration(file, *r).has_value());
  const auto back = read_headset_registration(file);
  ASSERT_TRUE(back.has_value()) << back.error();
  EXPECT_LT(angle_deg(back->world_from_stage, r->world_from_stage), 1e-9);
  EXPECT_LT(distance_mm(back->world_from_stage, r->world_from_stage), 1e-9);
  EXPECT_LT(distance_mm(back->head_from_star, r->head_from_star), 1e-9);
  EXPECT_EQ(back->samples, r->samples);

  const std::filesystem::path sheared = dir / "sheared.yaml";
  std::ofstream(sheared) << "%YAML:1.0\n---\nworld_from_stage: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n"
                            "   data: [ 1., 0.5, 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1. ]\n";
  const auto s = read_headset_registration(sheared);
  ASSERT_FALSE(s.has_value());
  EXPECT_EQ(s.error(), sheared.string() +
                           ": world_from_stage: not a rigid transform (its rotation is not orthonormal, or its last row is not 0 0 0 1)");
  const std::filesystem::path missing = dir / "missing.yaml";
  std::ofstream(missing) << "%YAML:1.0\n---\nrms_mm: 1.0\n";
  const auto m = read_headset_registration(missing);
  ASSERT_FALSE(m.has_value());
  EXPECT_EQ(m.error(), missing.string() + ": world_from_stage: missing");
  const auto none = read_headset_registration(dir / "nonexistent.yaml");
  ASSERT_FALSE(none.has_value());
  EXPECT_EQ(none.error(), (dir / "nonexistent.yaml").string() + ": cannot be read as OpenCV YAML");
  EXPECT_TRUE(write_registration_picture(dir / "residuals.png", look_around(30.0, 40.0, 15.0, 0.5, 0, 9), *r).has_value());
  EXPECT_GT(std::filesystem::file_size(dir / "residuals.png"), 1000u);
}

}  // namespace
}  // namespace rhot
