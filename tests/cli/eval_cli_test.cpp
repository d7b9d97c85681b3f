// Runs the real rhot-eval and checks its JSON.

#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/RunCommand.h"
#include "tracking/camera/Camera.h"
#include "tracking/camera/RigFile.h"
#include "tracking/hand/HandLayout.h"
#include "tracking/sim/HandMotions.h"
#include "tracking/sim/Realism.h"
#include "tracking/take/QualisysTsv.h"

namespace {

using EvalRun = rhot::test::CommandRun;

// stdout only: the JSON.
EvalRun run_eval(const std::string& args) { return rhot::test::run_program("rhot-eval", args, "2>/dev/null"); }

// A report without what may change from run to run or with the thread count: times (keys ending
// in _ms or _us) and the threads themselves.
nlohmann::json without_timings(nlohmann::json j) {
  if (j.is_array()) {
    for (nlohmann::json& e : j) e = without_timings(e);
  } else if (j.is_object()) {
    for (auto it = j.begin(); it != j.end();) {
      const std::string& k = it.key();
      const auto ends = [&k](std::string_view end) {
        return k.size() >= end.size() && k.compare(k.size() - end.size(), end.size(), end) == 0;
      };
      if (k == "threads" || ends("_ms") || ends("_us")) {
        it = j.erase(it);
      } else {
        *it = without_timings(*it);
        ++it;
      }
    }
  }
  return j;
}

TEST(EvalCli, TriangulationPrintsTheAccuracyJsonForEveryShippedRig) {
  // No volume flags: each rig file's tracking volume is where the markers move.
  for (const char* rig : {"seated-4.yaml", "room-8.yaml", "stereo-2.yaml"}) {
    const EvalRun r = run_eval(std::string("triangulation --rig ") + RHOT_ASSET_DIR + "/rigs/" + rig + " --frames 3 --markers 30 --json");
    ASSERT_EQ(r.exit_code, 0) << rig << "\n" << r.output;
    const nlohmann::json j = nlohmann::json::parse(r.output);
    for (const char* key :
         {"rms_mm", "crlb_mm", "ratio", "found_fraction", "ghosts", "median_ms", "p99_ms", "error_median_mm", "error_p95_mm"}) {
      EXPECT_TRUE(j.contains(key)) << rig << " lacks " << key;
    }
    EXPECT_GT(j["crlb_mm"].get<double>(), 0.0) << rig;
    EXPECT_GT(j["found_fraction"].get<double>(), 0.9) << rig;
    // RMS error over the Cramer-Rao bound: 1.00 over 200 frames (docs/PERFORMANCE.md, the target
    // at most 1.10); these 90 points pin it to about 4 % and give 1.06 (seated-4), 1.15 (room-8) and
    // 0.94 (stereo-2). Far above 1, the triangulation wastes accuracy; far below, the bound or the
    // noise is wrong.
    EXPECT_LT(j["ratio"].get<double>(), 1.25) << rig;
    EXPECT_GT(j["ratio"].get<double>(), 0.8) << rig;
    // Nearly every marker in the rig's volume is seen by two cameras or more.
    EXPECT_GT(j["findable_per_frame"].get<double>(), 20.0) << rig;
  }
}

TEST(EvalCli, VolumeFlagsOverrideTheRigFile) {
  const EvalRun r = run_eval(std::string("triangulation --rig ") + RHOT_ASSET_DIR +
                             "/rigs/seated-4.yaml --volume-centre-m 0 1.2 -0.4 --volume-m 0.2 0.3 0.4 --frames 2 --markers 5 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["volume_centre_m"], nlohmann::json({0.0, 1.2, -0.4}));
  EXPECT_EQ(j["volume_size_m"], nlohmann::json({0.2, 0.3, 0.4}));
}

TEST(EvalCli, WandLengthIsMeasuredToAboutAMillimetre) {
  const EvalRun r = run_eval(std::string("wand --rig ") + RHOT_ASSET_DIR + "/rigs/seated-4.yaml --length-mm 195 --frames 40 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["frames_measured"], 40);
  // Sigma 0.3 px on the seated rig: the true rig measures a wand's length to 0.38 mm RMS over
  // 1,000 frames (docs/PERFORMANCE.md; these 40 give 0.34 mm). At most twice that: a wrong scale
  // or a swapped end is far beyond.
  const double rms = j["rms_error_mm"].get<double>();
  EXPECT_LT(rms, 0.8);
  EXPECT_GT(rms, 0.05) << "noise-free results would mean the noise is not applied";
  // mean_error_mm is the mean absolute error: sqrt(2 / pi) = 0.80 of the RMS for Gaussian errors
  // (these 40 frames: 0.82). A bias, such as a scale off, would bring it to the RMS; a signed mean
  // would be near 0.
  EXPECT_NEAR(j["mean_error_mm"].get<double>() / rms, std::sqrt(2.0 / M_PI), 0.1);
}

TEST(EvalCli, BadRigIsReported) {
  const EvalRun r = run_eval("triangulation --rig /nonexistent.yaml --json");
  EXPECT_EQ(r.exit_code, 1);
}

TEST(EvalCli, ANoiseNoSimulationCanUseIsAClearError) {
  // NaN gets through the flag's range check; the simulated rig's settings check refuses it.
  const std::string stars = std::string("stars --set ") + RHOT_ASSET_DIR + "/stars/seed-case.json";
  for (const std::string& mode : {std::string("triangulation"), std::string("wand"), stars, std::string("hands")}) {
    const auto r = rhot::test::run_program("rhot-eval",
                                           mode + " --rig " + RHOT_ASSET_DIR + "/rigs/seated-4.yaml --sigma nan --frames 2 --json", "2>&1");
    EXPECT_EQ(r.exit_code, 1) << mode << "\n" << r.output;
    // stars and hands take the simulated world's flags, checked before any simulation.
    const bool world = mode == stars || mode == "hands";
    EXPECT_NE(r.output.find(world ? "rhot-eval: --sigma: expected a finite number"
                                  : "rhot-eval: sigma_px: expected a pixel noise of 0 or more, got nan"),
              std::string::npos)
        << mode << "\n"
        << r.output;
  }
}

TEST(EvalCli, ANonFiniteVolumeIsAClearError) {
  const auto r = rhot::test::run_program(
      "rhot-eval", std::string("triangulation --rig ") + RHOT_ASSET_DIR + "/rigs/seated-4.yaml --volume-m nan 1 1 --frames 2 --json",
      "2>&1");
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "--volume-m: expected a finite number, got nan\nRun with --help for more information.\n");
}

TEST(EvalCli, HandsReportsJointErrorsForEveryMotion) {
  const EvalRun r = run_eval(std::string("hands --rig ") + RHOT_ASSET_DIR + "/rigs/seated-4.yaml --motion all --frames 30 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  for (const char* motion : {"open", "fist", "pinch", "wave", "power-grasp", "precision-grasp"}) {
    ASSERT_TRUE(j["motions"].contains(motion)) << motion;
    for (const char* key : {"fingertip_mean_mm", "fingertip_p95_mm", "joint_mean_mm", "joint_p95_mm", "joints_with_confidence_fraction",
                            "ik_median_us", "ik_p99_us"}) {
      EXPECT_TRUE(j["motions"][motion].contains(key)) << motion << " " << key;
    }
  }
  // The open hand shows every fingertip: millimetre accuracy, and noise is applied.
  EXPECT_LT(j["motions"]["open"]["fingertip_mean_mm"].get<double>(), 3.0);
  EXPECT_GT(j["motions"]["open"]["fingertip_mean_mm"].get<double>(), 0.05);
  EXPECT_EQ(j["motions"]["open"]["hand_seen_fraction"].get<double>(), 1.0);
}

// The hand frame filter (on by default; --no-filter-frame turns it off) steadies the hand frame the
// hand star gives: with the user's own hand calibrated, the seen fingertips of an open hand jitter
// less (measured, seed 1: p95 2.35 mm against 2.92, mean 1.10 against 1.29).
TEST(EvalCli, HandsWithTheFrameFilteredHaveSteadierFingertips) {
  const auto run = [](const std::string& extra) {
    const EvalRun r = run_eval(std::string("hands --rig ") + RHOT_ASSET_DIR +
                               "/rigs/seated-4.yaml --motion open --frames 300 --sigma 0.5 --strays 3 --truth-hand independent "
                               "--calibrate-hand --seed 1 --json" +
                               extra);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return nlohmann::json::parse(r.output);
  };
  const nlohmann::json plain = run(" --no-filter-frame"), filtered = run("");
  EXPECT_FALSE(plain.at("filter_frame").get<bool>());
  EXPECT_TRUE(filtered.at("filter_frame").get<bool>());
  const nlohmann::json& a = plain.at("motions").at("open");
  const nlohmann::json& b = filtered.at("motions").at("open");
  EXPECT_LT(b.at("fingertip_p95_mm").get<double>(), a.at("fingertip_p95_mm").get<double>() - 0.3) << plain.dump() << filtered.dump();
  EXPECT_LT(b.at("fingertip_mean_mm").get<double>(), a.at("fingertip_mean_mm").get<double>());
}

TEST(EvalCli, TheLeftHandLayoutWorksToo) {
  const EvalRun r = run_eval(std::string("hands --rig ") + RHOT_ASSET_DIR + "/rigs/seated-4.yaml --layout " + RHOT_ASSET_DIR +
                             "/hands/low-cost-left.json --motion open --frames 30 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_LT(j["motions"]["open"]["fingertip_mean_mm"].get<double>(), 3.0);
  EXPECT_GT(j["motions"]["open"]["fingertips_seen_fraction"].get<double>(), 0.9);
}

TEST(EvalCli, TheHighFidelityLayoutFollowsAFist) {
  // Stars on the bones: a fist, which hides the low-cost layout's fingertips, is measured.
  const EvalRun r = run_eval(std::string("hands --rig ") + RHOT_ASSET_DIR + "/rigs/seated-4.yaml --layout " + RHOT_ASSET_DIR +
                             "/hands/high-fidelity-right.json --motion fist --frames 90 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output)["motions"]["fist"];
  EXPECT_LT(j["joint_mean_mm"].get<double>(), 4.0);
  EXPECT_GT(j["joint_mean_mm"].get<double>(), 0.1);
  EXPECT_GT(j["segment_stars_seen_fraction"].get<double>(), 0.6);
  EXPECT_GT(j["joints_with_confidence_fraction"].get<double>(), 0.95);
}

TEST(EvalCli, GraspPrintsTheScenarioJson) {
  const EvalRun r = run_eval("grasp --scenario lift --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  for (const char* key : {"lift_success_fraction", "max_slip_mm", "step_p50_ms", "step_p99_ms"}) EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["lift_success_fraction"].get<double>(), 1.0);
  EXPECT_LT(j["max_slip_mm"].get<double>(), 5.0);
  EXPECT_TRUE(j["scenarios"]["lift"]["grasped"].get<bool>());
  // Each grasp and release says why, as the overlay does (the index 17 mm out on its first frame
  // out, let go open_for_s later).
  std::vector<std::string> reasons;
  for (const nlohmann::json& e : j["scenarios"]["lift"]["events"]) {
    if (e["type"] == "grasp" || e["type"] == "release") reasons.push_back(e.value("reason", std::string("(none)")));
  }
  EXPECT_EQ(reasons, (std::vector<std::string>{"thumb against index", "index opened 22 mm (measured, last bone)"}));
  // Through tracked hands, against the same scenario with perfect hands: its one grasp made, never
  // let go early; the same on one thread as on two (issue 40: every mode's --threads changes no
  // result).
  const EvalRun tracked = run_eval("grasp --scenario lift --hands tracked --threads 2 --json");
  ASSERT_EQ(tracked.exit_code, 0) << tracked.output;
  const nlohmann::json g = nlohmann::json::parse(tracked.output);
  EXPECT_EQ(g["threads"].get<int>(), 2);
  const EvalRun one_thread = run_eval("grasp --scenario lift --hands tracked --threads 1 --json");
  ASSERT_EQ(one_thread.exit_code, 0) << one_thread.output;
  EXPECT_EQ(without_timings(nlohmann::json::parse(one_thread.output)), without_timings(g));
  EXPECT_EQ(g["grasp_cycles"].get<int>(), 1) << g.dump(2);
  EXPECT_EQ(g["tracked_grasps"].get<int>(), 1);
  EXPECT_EQ(g["missed_grasp_count"].get<int>(), 0);
  EXPECT_EQ(g["unintended_release_count"].get<int>(), 0);
  EXPECT_EQ(g["late_release_count"].get<int>(), 0);
  EXPECT_EQ(g["unintended_grasp_count"].get<int>(), 0);
  const EvalRun t = run_eval("grasp --scenario throw --json");
  ASSERT_EQ(t.exit_code, 0) << t.output;
  EXPECT_LT(nlohmann::json::parse(t.output)["throw_velocity_error_pct"].get<double>(), 10.0);
  const auto bad = rhot::test::run_program("rhot-eval", "grasp --scenario juggle --json", "2>&1");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("--scenario juggle: no such scenario (lift, pinch, throw, push, hand-over, hidden-markers, place, all)"),
            std::string::npos)
      << bad.output;
}

TEST(EvalCli, InteractionsRunsTheWorkbenchShowcasePerSeed) {
  // The script's own hands: every interaction succeeds in each of two runs, nothing pressed that
  // was not poked.
  const EvalRun r = run_eval("interactions --seeds 2 --hands perfect --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["seeds"].get<int>(), 2);
  EXPECT_EQ(j["success_fraction"].get<double>(), 1.0);
  EXPECT_EQ(j["false_press_count"].get<int>(), 0);
  for (const char* name : {"door-open", "drawer-open", "lamp-on", "peg-in", "bar-to-rack"}) {
    ASSERT_TRUE(j["interactions"].contains(name)) << name;
    EXPECT_EQ(j["interactions"][name]["success_fraction"].get<double>(), 1.0) << name;
    EXPECT_GT(j["interactions"][name]["time_to_success_s"]["median"].get<double>(), 0.0) << name;
  }
  EXPECT_EQ(j["interactions"]["bar-to-rack"]["events"]["grasp"].get<int>(), 4) << "two hands, twice";
  EXPECT_EQ(j["interactions"]["peg-in"]["events"]["snap"].get<int>(), 2);
  ASSERT_EQ(j["runs"].size(), 2u);
  // A scene with nothing to exercise is refused.
  const auto none = rhot::test::run_program("rhot-eval", "interactions --scene " RHOT_ASSET_DIR "/scenes/default.json --json", "2>&1");
  EXPECT_EQ(none.exit_code, 1);
  EXPECT_NE(none.output.find("default.json: nothing for the showcase script to exercise (no value_above, press or snap rules; "
                             "docs/scene-format.md)"),
            std::string::npos)
      << none.output;
}

TEST(EvalCli, InteractionsThroughTrackedHandsReportHiddenAndSeenFingertipsAndTimeAgainstPerfectHands) {
  // Through the seated rig's cameras in the realistic world (the table and the objects hide
  // markers): each interaction reports its fingertips seen and hidden against the truth, how many
  // were hidden, and its time against the script's own hands (measured on seed 1: seen 4.8-6.2 mm,
  // hidden 23-35 mm, 0.17-0.45 of them hidden, 1.000-1.003 of the perfect hands' time).
  const EvalRun r = run_eval("interactions --seeds 1 --seed 1 --hands tracked --world realistic --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["hands"].get<std::string>(), "tracked");
  EXPECT_EQ(j["world"]["name"].get<std::string>(), "realistic");
  int succeeded = 0;
  for (const char* name : {"door-open", "drawer-open", "lamp-on", "peg-in", "bar-to-rack"}) {
    ASSERT_TRUE(j["interactions"].contains(name)) << name;
    const nlohmann::json& one = j["interactions"][name];
    const double seen_mm = one["fingertip_error_seen_mm"].get<double>();
    const double hidden_mm = one["fingertip_error_hidden_mm"].get<double>();
    const double hidden_fraction = one["fingertip_hidden_fraction"].get<double>();
    EXPECT_GT(seen_mm, 0.0) << name;
    EXPECT_LT(seen_mm, 10.0) << name;
    // A hidden fingertip is estimated, a seen one measured: never the better of the two.
    EXPECT_GT(hidden_mm, seen_mm) << name;
    EXPECT_GT(hidden_fraction, 0.05) << name;
    EXPECT_LT(hidden_fraction, 0.7) << name;
    if (one["success_fraction"].get<double>() < 1.0) continue;
    ++succeeded;
    ASSERT_TRUE(one.contains("time_over_perfect_median")) << name;
    EXPECT_GE(one["time_over_perfect_median"].get<double>(), 0.95) << name;
    EXPECT_LE(one["time_over_perfect_median"].get<double>(), 1.2) << name;
  }
  EXPECT_GE(succeeded, 4);
  // Over the whole run, the same keys.
  EXPECT_GT(j["fingertip_error_hidden_mm"].get<double>(), j["fingertip_error_seen_mm"].get<double>());
  EXPECT_EQ(j["grasp_cycles"].get<int>(), 5);
  EXPECT_EQ(j["unintended_release_count"].get<int>(), 0);
}

TEST(EvalCli, FramePrintsTheWholeFrameAndEveryStage) {
  const EvalRun r = run_eval("frame --eye 64x64 --frames 20 --device cpu --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  for (const char* key : {"p50_ms", "p99_ms", "budget_miss_fraction"}) EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["frames"].get<int>(), 20);
  EXPECT_EQ(j["eye_px"], nlohmann::json::array({64, 64}));
  for (const char* stage : {"source", "matching", "stars", "hands", "transforms", "physics", "render"}) {
    ASSERT_TRUE(j["stages"].contains(stage)) << stage;
    EXPECT_GT(j["stages"][stage]["p50_ms"].get<double>(), 0.0) << stage;
    // A stage is timed inside its frame: never longer than the frame.
    EXPECT_LE(j["stages"][stage]["max_ms"].get<double>(), j["max_ms"].get<double>()) << stage;
  }
  // The stages are the frame: their mean times add up to the frame's, less only the few
  // microseconds between them (measured: 99.996 %).
  double stages_ms = 0.0;
  for (const auto& stage : j["stages"]) stages_ms += stage["mean_ms"].get<double>();
  EXPECT_LE(stages_ms, j["mean_ms"].get<double>());
  EXPECT_GT(stages_ms, 0.9 * j["mean_ms"].get<double>());
  // Latency: every frame but the last displayed, each at a refresh after its capture; the hands
  // measured against the truth, predicted.
  EXPECT_EQ(j["latency"]["frames"].get<int>(), 19);
  EXPECT_GT(j["tracking_latency_p99_ms"].get<double>(), 0.0);
  // Motion-to-photon is tracking, then rendering, then waiting for the GPU and the refresh: in the
  // mean (means add up, percentiles do not) at least the first two together.
  const nlohmann::json& latency = j["latency"];
  EXPECT_GE(latency["motion_to_photon_ms"]["mean"].get<double>(),
            latency["tracking_ms"]["mean"].get<double>() + latency["render_ms"]["mean"].get<double>());
  EXPECT_DOUBLE_EQ(j["motion_to_photon_p99_ms"].get<double>(), latency["motion_to_photon_ms"]["p99"].get<double>());
  EXPECT_GT(j["motion_to_photon_p50_ms"].get<double>(), j["latency"]["tracking_ms"]["p50"].get<double>());
  EXPECT_EQ(j["prediction"], "on");
  EXPECT_GT(j["prediction_errors"]["joint_samples"].get<int>(), 0);
  EXPECT_GT(j["prediction_error_ratio"].get<double>(), 0.0);
  const EvalRun off = run_eval("frame --eye 64x64 --frames 20 --device cpu --prediction off --json");
  ASSERT_EQ(off.exit_code, 0) << off.output;
  const nlohmann::json k = nlohmann::json::parse(off.output);
  EXPECT_EQ(k["prediction_errors"]["horizon_mean_ms"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(k["prediction_error_ratio"].get<double>(), k["prediction_errors"]["ratio_unpredicted"].get<double>());
  const auto bad_prediction = rhot::test::run_program("rhot-eval", "frame --prediction maybe --json", "2>&1");
  EXPECT_NE(bad_prediction.exit_code, 0);
  EXPECT_NE(bad_prediction.output.find("--prediction"), std::string::npos) << bad_prediction.output;
  const auto bad = rhot::test::run_program("rhot-eval", "frame --eye 64by64 --json", "2>&1");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("--eye: expected WIDTHxHEIGHT, each 16 to 8192 pixels, such as 1080x1200, got \"64by64\""), std::string::npos)
      << bad.output;
}

TEST(EvalCli, UnknownHandMotionIsNamed) {
  const auto r = rhot::test::run_program(
      "rhot-eval", std::string("hands --rig ") + RHOT_ASSET_DIR + "/rigs/seated-4.yaml --motion juggle --json", "2>&1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("--motion juggle: no such motion (open, fist, pinch, wave, power-grasp, precision-grasp, all)"),
            std::string::npos)
      << r.output;
}

}  // namespace

namespace {

// A 20 s glove take at 100 Hz as Qualisys exports it (gaps as "nan"): three markers on the back of
// a hand that moves and turns, a middle and a tip marker on each of five fingers that curl together
// with a motion of their own each (tests/tracking/hand/hidden_markers_test.cpp has the same hand).
std::string write_glove_take() {
  const std::string file = ::testing::TempDir() + "/eval_cli_glove.tsv";
  std::FILE* out = std::fopen(file.c_str(), "w");
  const char* fingers[] = {"thumb", "index", "middle", "ring", "little"};
  std::fprintf(out, "NO_OF_FRAMES\t2000\nNO_OF_MARKERS\t13\nFREQUENCY\t100\nMARKER_NAMES\thand_top\thand_left\thand_right");
  for (const char* f : fingers) std::fprintf(out, "\t%s_tip\t%s_middle", f, f);
  std::fprintf(out, "\n");
  for (int frame = 0; frame < 2000; ++frame) {
    const double t = frame / 100.0, yaw = 0.5 * std::sin(0.4 * t), c = std::cos(yaw), s = std::sin(yaw);
    const auto put = [&](double x, double y, double z) {
      if (frame % 997 == 5) {  // a gap now and then, as the capture system writes it
        std::fprintf(out, "\tnan\tnan\tnan");
        return;
      }
      std::fprintf(out, "\t%.3f\t%.3f\t%.3f", 1e3 * (c * x - s * y + 0.1 * std::sin(0.3 * t)), 1e3 * (s * x + c * y + 1.0), 1e3 * z);
    };
    std::fprintf(out, "%d\t%.5f", frame + 1, t);
    put(0.0, 0.02, 0.0);
    put(-0.03, -0.02, 0.0);
    put(0.03, -0.02, 0.0);
    const double grasp = 0.7 + 0.6 * std::sin(2.0 * 3.14159265358979 * 0.3 * t);
    for (int i = 0; i < 5; ++i) {
      const double bend = grasp * (0.9 + 0.05 * i) + 0.15 * std::sin(2.0 * 3.14159265358979 * (0.5 + 0.17 * i) * t + i);
      const double bx = -0.04 + 0.02 * i, my = 0.05 + 0.045 * std::cos(bend), mz = -0.045 * std::sin(bend);
      put(bx, my + 0.035 * std::cos(2.2 * bend), mz - 0.035 * std::sin(2.2 * bend));
      put(bx, my, mz);
    }
    std::fprintf(out, "\n");
  }
  std::fclose(out);
  return file;
}

TEST(EvalCli, AHandModelFittedToATakesFirstPartEstimatesItsHiddenTipsInTheRest) {
  const std::string take = write_glove_take(), model = ::testing::TempDir() + "/eval_cli_glove_model.json";
  const auto fit =
      rhot::test::run_program("rhot-calib", "hand-model --take " + take + " --out " + model + " --fit-seconds 12 --json", "2>/dev/null");
  ASSERT_EQ(fit.exit_code, 0) << fit.output;
  EXPECT_EQ(nlohmann::json::parse(fit.output).at("markers").size(), 10u);
  const auto r = run_eval("hands --take " + take + " --labelled --model " + model + " --evaluate-from-s 12 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j.at("evaluated_frames")[0], 1201);
  EXPECT_GT(j.at("estimated_frames").get<int>(), 300);
  // Measured: 1.5 mm hidden against 15 mm held where it was last seen (390 frames).
  EXPECT_LT(j.at("hidden_tip_mean_mm").get<double>(), 4.0);
  EXPECT_LT(j.at("hidden_tip_mean_mm").get<double>(), 0.25 * j.at("held_tip_mean_mm").get<double>());
  EXPECT_EQ(j.at("fingers").size(), 5u);

  const auto no_labels = rhot::test::run_program("rhot-eval", "hands --take " + take + " --json", "2>&1 >/dev/null");
  EXPECT_EQ(no_labels.exit_code, 1);
  EXPECT_EQ(no_labels.output,
            "rhot-eval: hands --take: --labelled (the take's 3D points) or --rig FILE (the take photographed by the rig's cameras), one "
            "of them\n");
  // CLI11's Range lets nan through (every comparison with it is false); it reached a float-to-int cast.
  for (const char* flag : {"--hide-gap-s", "--fit-fraction"}) {
    const auto nan =
        rhot::test::run_program("rhot-eval", "hands --take " + take + " --labelled " + flag + " nan --json", "2>&1 >/dev/null");
    EXPECT_EQ(nan.exit_code, 1) << flag;
    EXPECT_NE(nan.output.find("expected a finite number, got nan"), std::string::npos) << flag << ": " << nan.output;
  }
}

// A 20 s take at 100 Hz of the 13-marker glove (assets/hands/glove-13-right.json) on a hand with its
// own bones and angles, closing into a power grasp and opening again as it moves, written as
// Qualisys writes it; its index tip marker named "IndexTip" (a name --map must give), and the
// positions divided by `units` (1000: metres written where millimetres are said).
std::string write_simulated_glove_take(const std::string& name, double units) {
  const auto layout = rhot::load_hand_layout(std::string(RHOT_ASSET_DIR) + "/hands/glove-13-right.json");
  EXPECT_TRUE(layout.has_value());
  const rhot::HandPose model = rhot::reference_open_hand(rhot::HandSide::kRight);
  const auto chains = rhot::hand_chains(model, rhot::HandSide::kRight);
  const auto relaxed = rhot::HandSolver(rhot::HandSide::kRight, model).state().angles;
  const rhot::HandPose user = rhot::independent_hand(model, 3);
  const auto user_chains = rhot::hand_chains(user, rhot::HandSide::kRight);
  rhot::MarkerTake take;
  take.frame_rate_hz = 100.0;
  take.marker_names = rhot::layout_marker_names(*layout);
  take.marker_names[4] = "IndexTip";
  for (int f = 0; f < 2000; ++f) {
    const double t = f / 100.0;
    const auto truth = rhot::hand_motion("power-grasp", t, chains, relaxed, {0.0, 1.1, -0.45});
    const rhot::HandPose pose = rhot::hand_pose_from_angles(user, user_chains, rhot::independent_angles(truth->angles, 3));
    for (const Eigen::Vector3d& m : rhot::layout_markers(*layout, truth->world_from_hand, pose)) take.positions_m.push_back(m / units);
  }
  const std::string file = ::testing::TempDir() + "/" + name;
  EXPECT_TRUE(rhot::write_qualisys_tsv(take, file).has_value());
  return file;
}

// A take's labelled markers through the hand tracker (its fingertip model fitted as it runs, its IK,
// a hand whose bones are not the tracker's): each fingertip hidden in turn for 0.5 s.
TEST(EvalCli, ATakesLabelledMarkersDriveTheHandTrackerThroughALayout) {
  const std::string take = write_simulated_glove_take("eval_cli_sim_glove.tsv", 1.0);
  const std::string layout = std::string(RHOT_ASSET_DIR) + "/hands/glove-13-right.json";
  const auto r = run_eval("hands --take " + take + " --layout " + layout + " --labelled --map IndexTip=index_tip --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  SCOPED_TRACE(r.output);
  EXPECT_EQ(j.at("hand_seen_fraction").get<double>(), 1.0);
  EXPECT_GE(j.at("fingertip_model_frames").get<int>(), 90);
  EXPECT_EQ(j.at("hidden_frames").get<int>(), 1000) << "one tip hidden in half the frames (0.5 s hidden, 0.5 s seen)";
  EXPECT_EQ(j.at("fingers").size(), 5u);
  // Measured: hidden 0.57 mm mean (p95 1.45), seen 0.43 mm, held where last seen 26 mm (with
  // FABRIK reaching for the tip joint alone, before each finger was fitted to all its markers:
  // hidden 2.1 mm, seen 1.6 mm).
  EXPECT_LT(j.at("hidden_tip_mean_mm").get<double>(), 1.2);
  EXPECT_LT(j.at("hidden_tip_mean_mm").get<double>(), 0.5 * j.at("held_tip_mean_mm").get<double>());
  EXPECT_LT(j.at("visible_tip_mean_mm").get<double>(), 0.9);
  EXPECT_FALSE(j.at("filter").get<bool>());
  EXPECT_FALSE(j.at("filter_frame").get<bool>()) << "a labelled frame is as recorded, whatever the default";

  // --filter reaches the tracker (it was once ignored with --take): the 1-euro filter smooths the
  // seen markers, so on this moving hand the seen tips lag behind the take's (measured: 2.56 mm
  // against 0.43 mm unfiltered).
  const auto filtered = run_eval("hands --take " + take + " --layout " + layout + " --labelled --map IndexTip=index_tip --filter --json");
  ASSERT_EQ(filtered.exit_code, 0) << filtered.output;
  const auto f = nlohmann::json::parse(filtered.output);
  EXPECT_TRUE(f.at("filter").get<bool>());
  EXPECT_GT(f.at("visible_tip_mean_mm").get<double>(), 2.0 * j.at("visible_tip_mean_mm").get<double>()) << filtered.output;

  // Named windows in place of the rule: the index finger's two markers hidden together for a second
  // as the hand closes, the thumb's tip for half a second after; the rest seen.
  const auto named =
      run_eval("hands --take " + take + " --layout " + layout +
               " --labelled --map IndexTip=index_tip --hide index_tip@5-6 --hide index_middle@5-6 --hide thumb_tip@7000e-3-7.5 --json");
  ASSERT_EQ(named.exit_code, 0) << named.output;
  const auto n = nlohmann::json::parse(named.output);
  SCOPED_TRACE(named.output);
  EXPECT_EQ(n.at("hidden_frames").get<int>(), 150);
  EXPECT_EQ(n.at("fingers").at("index_tip").at("hidden_frames").get<int>(), 100);
  EXPECT_EQ(n.at("fingers").at("thumb_tip").at("hidden_frames").get<int>(), 50);
  EXPECT_EQ(n.at("hidden_markers").at("index_middle").at("hidden_frames").get<int>(), 100);
  // The middle marker hidden with its tip: placed from the other fingers alone (measured 2.2 mm).
  EXPECT_LT(n.at("hidden_markers").at("index_middle").at("hidden_mean_mm").get<double>(), 5.0);
  EXPECT_EQ(n.at("hide").size(), 3u);
  EXPECT_LT(n.at("hidden_tip_mean_mm").get<double>(), 0.5 * n.at("held_tip_mean_mm").get<double>());

  const auto refused = [&](const std::string& args) {
    const auto out = rhot::test::run_program("rhot-eval", "hands --take " + args + " --labelled --json", "2>&1 >/dev/null");
    EXPECT_EQ(out.exit_code, 1) << args;
    return out.output;
  };
  EXPECT_EQ(refused(take + " --layout " + layout),
            "rhot-eval: " + take +
                ": the take has no marker for the layout's \"index_tip\" (its markers: hand_top, hand_left, hand_right, thumb_tip, "
                "IndexTip, middle_tip, ring_tip, little_tip, thumb_middle, index_middle, middle_middle, ring_middle, little_middle; "
                "name one with --map TAKE_NAME=LAYOUT_NAME)\n");
  EXPECT_EQ(refused(take + " --layout " + layout + " --map IndexTip"),
            "rhot-eval: " + take + ": --map IndexTip: expected TAKE_NAME=LAYOUT_NAME\n");
  EXPECT_EQ(refused(take + " --layout " + layout + " --map IndexTip=index_nail"),
            "rhot-eval: " + take + ": --map IndexTip=index_nail: the layout has no marker \"index_nail\"\n");
  EXPECT_EQ(refused(take + " --layout " + layout + " --model model.json"),
            "rhot-eval: hands --take: --model is the estimator's alone (without --layout); the tracker fits its own\n");
  EXPECT_EQ(refused(take + " --map IndexTip=index_tip"), "rhot-eval: hands --take: --map, --calibrate-seconds and --hide need --layout\n");
  EXPECT_EQ(refused(take + " --filter"),
            "rhot-eval: hands --take: --filter and --filter-frame need --layout (without it no tracker runs)\n");
  EXPECT_EQ(refused(take + " --layout " + layout + " --map IndexTip=index_tip --filter-frame"),
            "rhot-eval: hands --take --labelled: --filter-frame steadies a hand frame found from the cameras' points; labelled markers "
            "give it as recorded (--filter filters it and the fingertips)\n");
  const std::string mapped = take + " --layout " + layout + " --map IndexTip=index_tip";
  EXPECT_EQ(refused(mapped + " --hide index_tip:5-6"),
            "rhot-eval: --hide index_tip:5-6: expected MARKER@T0-T1 (seconds into the take), e.g. index_tip@12.5-13\n");
  EXPECT_EQ(
      refused(mapped + " --hide index_nail@5-6"),
      "rhot-eval: --hide index_nail@5-6: no marker \"index_nail\" in the layout (its finger markers: thumb_tip, index_tip, middle_tip, "
      "ring_tip, little_tip, thumb_middle, index_middle, middle_middle, ring_middle, little_middle)\n");
  EXPECT_EQ(refused(mapped + " --hide hand_top@5-6"),
            "rhot-eval: --hide hand_top@5-6: a marker on the back of the hand gives the hand its frame: hide finger markers\n");
  EXPECT_EQ(refused(mapped + " --hide index_tip@6-5"), "rhot-eval: --hide index_tip@6-5: the window ends before it starts\n");
  EXPECT_EQ(refused(mapped + " --hide index_tip@5-nan"),
            "rhot-eval: --hide index_tip@5-nan: the window's times must be seconds from 0 on, e.g. index_tip@12.5-13\n");
  EXPECT_EQ(refused(mapped + " --hide index_tip@19-21"),
            "rhot-eval: --hide index_tip@19-21: the window ends after the take's end (20.00 s)\n");
  EXPECT_EQ(refused(mapped + " --hide index_tip@5.001-5.009"),
            "rhot-eval: --hide index_tip@5.001-5.009: the window holds no frame of the take\n");
  const std::string metres = write_simulated_glove_take("eval_cli_sim_glove_metres.tsv", 1000.0);
  EXPECT_EQ(refused(metres + " --layout " + layout + " --map IndexTip=index_tip"),
            "rhot-eval: " + metres +
                ": the back of the hand's markers are 0.134 mm apart in all (frame 1) where the layout's are 132 mm: is the take in other "
                "units than it says?\n");
}

// The same take photographed by the seated rig's four cameras in the realistic world (0.5 px of
// noise, 2 % dropout, three strays a camera, 6 mm markers that merge where they overlap, 2 ms
// between the cameras' exposures, calibration 0.3 px off): the hand found by its back's three markers among
// unlabelled points (a triangle, TriangleTracker.h), the fingers' markers matched, the fingers
// fitted to the markers the tracker found in the first 3 s (--calibrate-from cameras), each
// fingertip hidden in turn.
TEST(EvalCli, ATakePhotographedByTheSeatedRigIsTrackedThroughItsCameras) {
  const std::string take = write_simulated_glove_take("eval_cli_sim_glove_rig.tsv", 1.0);
  const std::string layout = std::string(RHOT_ASSET_DIR) + "/hands/glove-13-right.json";
  const std::string rig = std::string(RHOT_ASSET_DIR) + "/rigs/seated-4.yaml";
  const auto r = run_eval("hands --take " + take + " --layout " + layout + " --map IndexTip=index_tip --rig " + rig +
                          " --world realistic --calibrate-seconds 3 --calibrate-from cameras --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  SCOPED_TRACE(r.output);
  EXPECT_EQ(j.at("through").get<std::string>(), "the rig's cameras");
  EXPECT_GE(j.at("hand_seen_fraction").get<double>(), 0.99);
  EXPECT_GT(j.at("calibration").at("frames").get<int>(), 200);
  // 17 s judged at the rig's 90 Hz, one tip hidden half the time.
  EXPECT_NEAR(j.at("hidden_frames").get<int>(), 765, 40);
  // Measured: hidden 1.05 mm (p95 1.9), seen 0.98 mm, 97.9 % of the finger markers in view found
  // and none of them elsewhere (the hand frame filtered, the default; unfiltered 1.23 mm, p95 2.6,
  // seen 1.06 mm); the same take labelled: 0.30 mm hidden.
  EXPECT_TRUE(j.at("filter_frame").get<bool>());
  EXPECT_LT(j.at("hidden_tip_mean_mm").get<double>(), 2.5);
  EXPECT_LT(j.at("visible_tip_mean_mm").get<double>(), 2.2);
  EXPECT_GE(j.at("finger_markers_found_fraction").get<double>(), 0.95);
  EXPECT_LE(j.at("finger_markers_wrong_fraction").get<double>(), 0.01);
  EXPECT_LT(j.at("hidden_tip_mean_mm").get<double>(), 0.5 * j.at("held_tip_mean_mm").get<double>());

  const auto refused = [&](const std::string& args) {
    const auto out = rhot::test::run_program("rhot-eval", "hands --take " + take + " " + args + " --json", "2>&1 >/dev/null");
    EXPECT_EQ(out.exit_code, 1) << args;
    return out.output;
  };
  EXPECT_EQ(refused("--layout " + layout + " --labelled --rig " + rig),
            "rhot-eval: hands --take: --labelled (the take's 3D points) or --rig FILE (the take photographed by the rig's cameras), one "
            "of them\n");
  EXPECT_EQ(refused("--rig " + rig), "rhot-eval: hands --take --rig: needs --layout (the markers the cameras follow)\n");
}

// Coloured markers through two colour cameras, 30 frames from 6.5 s into the demo's script, the
// left hand out of the cameras' view. Fingertip markers (their colours no star wears) beside blue
// star markers were taken for the left hand's star until the star tracker stopped seeing them: 6
// hand frames with a "left hand" 0.5 m from the true one, fingertips 90 mm off on average. Measured
// now: none, 2.2 mm.
TEST(EvalCli, ColourFingertipsAreNeverTakenForAHandStar) {
  // The shipped pair moved to head height and aimed past the mug (as it was before it was aimed at
  // the whole desk), so that at 6.5 s the left hand, at the mug, is out of view.
  auto pair = rhot::load_rig(std::string(RHOT_ASSET_DIR) + "/rigs/stereo-640.yaml");
  ASSERT_TRUE(pair) << pair.error();
  for (rhot::Camera& camera : pair->cameras) {
    const double side = camera.name == "left" ? -0.15 : 0.15;
    camera.cam_from_world = rhot::cam_from_world_look_at({side, 1.65, 0.2}, {0.0, 0.95, -0.45});
  }
  const std::string rig = ::testing::TempDir() + "/eval_cli_pair_ahead.yaml";
  ASSERT_TRUE(rhot::save_rig(*pair, rig));
  const EvalRun r = run_eval("colour --rig " + rig + " --frames 30 --start-s 6.5 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["frames"], 30);
  EXPECT_EQ(j["misplaced_hand_frames"], 0);
  EXPECT_EQ(j["hand_seen_fraction"], j["hand_in_view_fraction"]) << "the right hand seen in every frame, the left (out of view) in none";
  EXPECT_LT(j["fingertip_mean_mm"].get<double>(), 4.0);
  EXPECT_EQ(j["false_detections_per_image"], 0.0);
}

// A small crowd (one person: two hands, a headset and a prop on the back, among loose markers) at
// 120 Hz on stage-32, on two threads and again on one: the same results, every key of the report,
// and the bodies and hands against the truth. Measured (release, seeds 1-3): bodies 1.0, hands
// 1.0, found 0.97-0.98 (also over 3 s); seed 2's hands were correct in 0.90 of its frames, found
// 0.94, while matching refused a star marker that lined up with its neighbour in two cameras. And
// after the warm-up's half second the tracking (matching, stars, hands) allocates nothing: counted
// over every thread (tools/eval/AllocationCount.h), 3,559 to 4,323 allocations in the warm-up's
// frames (seeds 1-3), none after, also over 3 s.
TEST(EvalCli, ScaleRunsACrowdOnTwoThreadsWithTheResultsOfOne) {
  const EvalRun r = run_eval("scale --seconds 1 --markers 150 --bodies 2 --hands 2 --threads 2 --seed 2 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["threads"], 2);
  EXPECT_EQ(j["people"], 1);
  EXPECT_EQ(j["judged_frames"], 60) << "one second at 120 Hz less the half second of warm-up";
  EXPECT_EQ(j["same_results_as_one_thread"], true);
  for (const char* stage : {"matching", "stars", "hands"}) {
    ASSERT_TRUE(j["stages"].contains(stage)) << stage;
    EXPECT_GT(j["stages"][stage]["p99_ms"].get<double>(), 0.0) << stage;
    EXPECT_LE(j["stages"][stage]["p50_ms"].get<double>(), j["stages"][stage]["p99_ms"].get<double>()) << stage;
  }
  for (const char* key : {"frame_p99_ms", "missed_period_fraction", "speedup_vs_one_thread", "resident_mb_end", "hand_joint_error_mean_mm"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_GE(j["bodies_correct_fraction"].get<double>(), 0.95);
  EXPECT_GE(j["hands_correct_fraction"].get<double>(), 0.99) << "issue 40's target";
  EXPECT_GE(j["found_fraction"].get<double>(), 0.95);
  // The count counts: the first frames make the trackers' room.
  EXPECT_GT(j["warm_up_allocations"].get<long>(), 1000);
  EXPECT_EQ(j["allocating_frames"].get<long>(), 0);
  EXPECT_EQ(j["allocations_per_frame"].get<double>(), 0.0);
  for (const char* stage : {"matching", "stars", "hands"})
    EXPECT_EQ(j["stages"][stage]["allocations_per_frame"].get<double>(), 0.0) << stage;
}

TEST(EvalCli, ScaleRefusesARateOrThreadsItCannotUse) {
  const EvalRun nan_rate = rhot::test::run_program("rhot-eval", "scale --rate-hz nan --json", "2>&1");
  EXPECT_EQ(nan_rate.exit_code, 1) << nan_rate.output;
  EXPECT_NE(nan_rate.output.find("--rate-hz"), std::string::npos) << nan_rate.output;
  const EvalRun nan_sigma = rhot::test::run_program("rhot-eval", "scale --sigma nan --json", "2>&1");
  EXPECT_EQ(nan_sigma.exit_code, 1) << nan_sigma.output;
  EXPECT_NE(nan_sigma.output.find("--sigma"), std::string::npos) << nan_sigma.output;
  const EvalRun threads = rhot::test::run_program("rhot-eval", "scale --threads -1 --json", "2>&1");
  EXPECT_EQ(threads.exit_code, 1) << threads.output;
  EXPECT_NE(threads.output.find("--threads: Value -1 not in range 0 to 256"), std::string::npos) << threads.output;
}

}  // namespace
