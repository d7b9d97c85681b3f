// Runs rhot-demo --record and rhot-gltf, and reads the glTF back with tinygltf: the animation's
// samples are the recording's.

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include "tests/support/RunCommand.h"
#include "engine/tracked/Recording.h"

namespace {

// The floats of an accessor (tightly packed, as rhot-gltf writes them).
std::vector<float> floats(const tinygltf::Model& m, int accessor) {
  const tinygltf::Accessor& a = m.accessors[static_cast<std::size_t>(accessor)];
  const tinygltf::BufferView& v = m.bufferViews[static_cast<std::size_t>(a.bufferView)];
  const int components = a.type == TINYGLTF_TYPE_SCALAR ? 1 : a.type == TINYGLTF_TYPE_VEC3 ? 3 : 4;
  std::vector<float> out(a.count * static_cast<std::size_t>(components));
  std::memcpy(out.data(), m.buffers[static_cast<std::size_t>(v.buffer)].data.data() + v.byteOffset + a.byteOffset,
              out.size() * sizeof(float));
  return out;
}

TEST(GltfCli, ARecordingBecomesAnAnimatedGltf) {
  const std::string rec = ::testing::TempDir() + "rhot_cli_recording.jsonl";
  const std::string out = ::testing::TempDir() + "rhot_cli_recording.gltf";
  const auto demo = rhot::test::run_program("rhot-demo", "--headless --frames 60 --eye 64x64 --record " + rec, "2>&1");
  ASSERT_EQ(demo.exit_code, 0) << demo.output;
  const auto conv = rhot::test::run_program("rhot-gltf", rec + " --out " + out, "2>&1");
  ASSERT_EQ(conv.exit_code, 0) << conv.output;
  EXPECT_NE(conv.output.find("60 frames, 55 animated nodes"), std::string::npos) << conv.output;

  const auto recording = rhot::load_recording(rec);
  ASSERT_TRUE(recording.has_value()) << recording.error();
  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadASCIIFromFile(&m, &err, &warn, out)) << err;
  ASSERT_EQ(m.animations.size(), 1U);
  // Find right_index_tip's translation channel and compare its samples with the recording.
  int node = -1;
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    if (m.nodes[i].name == "right_index_tip") node = static_cast<int>(i);
  }
  ASSERT_GE(node, 0);
  bool checked = false;
  for (const auto& c : m.animations[0].channels) {
    if (c.target_node != node || c.target_path != "translation") continue;
    const auto& sampler = m.animations[0].samplers[static_cast<std::size_t>(c.sampler)];
    const auto times = floats(m, sampler.input);
    const auto values = floats(m, sampler.output);
    ASSERT_EQ(times.size(), recording->frames.size());
    for (std::size_t f = 0; f < times.size(); ++f) {
      const auto& hand = recording->frames[f].hands[1];
      if (!hand.seen) continue;
      const Eigen::Vector3d p = hand.joints_world[static_cast<std::size_t>(rhot::HandJoint::kIndexTip)];
      EXPECT_NEAR(values[3 * f], p.x(), 1e-6);
      EXPECT_NEAR(values[3 * f + 1], p.y(), 1e-6);
      EXPECT_NEAR(values[3 * f + 2], p.z(), 1e-6);
    }
    checked = true;
  }
  EXPECT_TRUE(checked);
  const auto bad = rhot::test::run_program("rhot-gltf", rec + ".missing --out " + out, "2>&1");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("rhot-gltf: " + rec + ".missing: cannot read the recording"), std::string::npos) << bad.output;
}

// A BVH file read back by a parser of the test's own: the hierarchy, then each frame's channels
// turned into joint positions by forward kinematics (a joint's translation is its OFFSET plus its
// position channels; its rotation the product of its rotation channels in the order listed).
struct BvhNode {
  std::string name;  // an End Site: its parent's name + "/end"
  int parent = -1;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  std::vector<std::string> channels;
};

struct Bvh {
  std::vector<BvhNode> nodes;
  double frame_time = 0.0;
  std::vector<std::vector<double>> frames;
};

Bvh read_bvh(const std::string& file) {
  std::ifstream in(file);
  Bvh b;
  std::vector<int> stack;
  std::string word;
  while (in >> word && word != "MOTION") {
    if (word == "ROOT" || word == "JOINT") {
      BvhNode n;
      in >> n.name;
      n.parent = stack.empty() ? -1 : stack.back();
      b.nodes.push_back(n);
    } else if (word == "End") {
      in >> word;  // "Site"
      b.nodes.push_back({b.nodes[static_cast<std::size_t>(stack.back())].name + "/end", stack.back(), Eigen::Vector3d::Zero(), {}});
    } else if (word == "{") {
      stack.push_back(static_cast<int>(b.nodes.size()) - 1);
    } else if (word == "}") {
      stack.pop_back();
    } else if (word == "OFFSET") {
      Eigen::Vector3d& o = b.nodes.back().offset;
      in >> o.x() >> o.y() >> o.z();
    } else if (word == "CHANNELS") {
      int n = 0;
      in >> n;
      b.nodes.back().channels.resize(static_cast<std::size_t>(n));
      for (auto& c : b.nodes.back().channels) in >> c;
    }
  }
  std::size_t count = 0;
  std::size_t values = 0;
  for (const BvhNode& n : b.nodes) values += n.channels.size();
  in >> word >> count >> word >> word >> b.frame_time;  // "Frames:" N "Frame" "Time:" T
  for (std::size_t f = 0; f < count; ++f) {
    b.frames.emplace_back(values);
    for (double& v : b.frames.back()) in >> v;
  }
  return b;
}

// Every node's world position in a frame.
std::map<std::string, Eigen::Vector3d> forward_kinematics(const Bvh& b, const std::vector<double>& frame) {
  std::vector<Eigen::Isometry3d> world(b.nodes.size());
  std::map<std::string, Eigen::Vector3d> out;
  std::size_t k = 0;
  for (std::size_t i = 0; i < b.nodes.size(); ++i) {
    const BvhNode& n = b.nodes[i];
    Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
    Eigen::Vector3d t = n.offset;
    Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
    for (const std::string& c : n.channels) {
      const double v = frame[k++];
      const double rad = v * std::numbers::pi / 180.0;
      if (c == "Xposition") t.x() += v;
      if (c == "Yposition") t.y() += v;
      if (c == "Zposition") t.z() += v;
      if (c == "Xrotation") r = r * Eigen::AngleAxisd(rad, Eigen::Vector3d::UnitX()).toRotationMatrix();
      if (c == "Yrotation") r = r * Eigen::AngleAxisd(rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
      if (c == "Zrotation") r = r * Eigen::AngleAxisd(rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    }
    local.linear() = r;
    local.translation() = t;
    world[i] = n.parent < 0 ? local : world[static_cast<std::size_t>(n.parent)] * local;
    out[n.name] = world[i].translation();
  }
  return out;
}

// The hands of a recording as BVH: the file's hierarchy holds both hands' 26 joints (the tips as
// End Sites), its frames are the recording's at its rate, and forward kinematics through the
// file's offsets and rotation channels puts every joint where the recording has it (0.1 mm;
// frames where the hand was seen).
TEST(GltfCli, ARecordingsHandsBecomeABvhSkeleton) {
  const std::string rec = ::testing::TempDir() + "rhot_cli_bvh.jsonl";
  const std::string out = ::testing::TempDir() + "rhot_cli_hands.bvh";
  const auto demo = rhot::test::run_program("rhot-demo", "--headless --frames 120 --eye 64x64 --record " + rec, "2>&1");
  ASSERT_EQ(demo.exit_code, 0) << demo.output;
  const auto conv = rhot::test::run_program("rhot-gltf", rec + " --format bvh --out " + out, "2>&1");
  ASSERT_EQ(conv.exit_code, 0) << conv.output;
  const auto recording = rhot::load_recording(rec);
  ASSERT_TRUE(recording.has_value()) << recording.error();

  const Bvh bvh = read_bvh(out);
  ASSERT_EQ(bvh.frames.size(), recording->frames.size());
  EXPECT_NEAR(bvh.frame_time, 1.0 / recording->rate_hz, 1e-6);
  int seen_frames = 0;
  double worst_m = 0.0;
  for (std::size_t f = 0; f < bvh.frames.size(); ++f) {
    const auto at = forward_kinematics(bvh, bvh.frames[f]);
    for (std::size_t h = 0; h < 2; ++h) {
      const rhot::HandInput& hand = recording->frames[f].hands[h];
      if (!hand.seen) continue;
      ++seen_frames;
      const std::string side = h == 0 ? "left_" : "right_";
      for (int j = 0; j < rhot::kHandJointCount; ++j) {
        std::string name = side + std::string(rhot::joint_name(static_cast<rhot::HandJoint>(j)));
        if (name.ends_with("_tip")) name = name.substr(0, name.size() - 3) + "distal/end";
        const auto it = at.find(name);
        ASSERT_NE(it, at.end()) << name;
        const double error_m = (it->second / 100.0 - hand.joints_world[static_cast<std::size_t>(j)]).norm();
        worst_m = std::max(worst_m, error_m);
        EXPECT_LT(error_m, 1e-4) << name << " in frame " << f;
      }
    }
  }
  EXPECT_GT(seen_frames, 100);
  EXPECT_GT(worst_m, 0.0);
  std::cerr << "worst joint " << 1000.0 * worst_m << " mm\n";
}

// A recording of three frames, written as rhot-demo --record writes it; `cut` keeps only the first
// 30 bytes of the third frame's line, without its newline, as a crash while it was written would.
std::string small_recording(const std::string& name, bool cut) {
  const std::string file = ::testing::TempDir() + name;
  {
    auto writer = rhot::RecordingWriter::open(file, 90.0, {});
    EXPECT_TRUE(writer.has_value()) << writer.error();
    for (int f = 0; f < 3; ++f) {
      rhot::RecordedFrame frame;
      frame.t_s = f / 90.0;
      frame.hands[1].seen = true;
      for (auto& p : frame.hands[1].joints_world) p = Eigen::Vector3d(0.01 * f, 1.0, -0.4);
      EXPECT_TRUE(writer->write(frame).has_value());
    }
  }
  if (!cut) return file;
  std::ifstream in(file, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  const std::string whole = text.str();
  const std::size_t last_line = whole.rfind('\n', whole.size() - 2) + 1;
  std::ofstream(file, std::ios::binary | std::ios::trunc) << whole.substr(0, last_line + 30);
  return file;
}

// CLI11's range check lets nan through (every comparison with it is false): it reached the mesh.
TEST(GltfCli, AJointSizeThatIsNotAFiniteNumberIsRefused) {
  const std::string rec = small_recording("rhot_cli_small.jsonl", false);
  const std::string out = ::testing::TempDir() + "rhot_cli_nan.gltf";
  std::remove(out.c_str());
  for (const char* size : {"nan", "inf"}) {
    const auto r = rhot::test::run_program("rhot-gltf", rec + " --joint-size-mm " + size + " --out " + out, "2>&1");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(std::string("--joint-size-mm: expected a finite number, got ") + size), std::string::npos) << r.output;
  }
  EXPECT_FALSE(std::ifstream(out).good()) << "nothing written";
  const auto fine = rhot::test::run_program("rhot-gltf", rec + " --joint-size-mm 5 --out " + out, "2>&1");
  EXPECT_EQ(fine.exit_code, 0) << fine.output;
}

// A recording a crash cut short converts: every whole frame, and one warning naming the line left out.
TEST(GltfCli, ARecordingCutShortByACrashConvertsWithAWarning) {
  const std::string rec = small_recording("rhot_cli_cut.jsonl", true);
  const std::string out = ::testing::TempDir() + "rhot_cli_cut.gltf";
  const auto r = rhot::test::run_program("rhot-gltf", rec + " --out " + out, "2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string warning =
      rec + ":4: the last line is cut short (was the recording interrupted?); it is left out, the 2 frames before it are read";
  const std::size_t at = r.output.find(warning);
  EXPECT_NE(at, std::string::npos) << r.output;
  EXPECT_EQ(r.output.find(warning, at + 1), std::string::npos) << "one warning:\n" << r.output;
  EXPECT_NE(r.output.find("2 frames, 52 animated nodes"), std::string::npos) << r.output;
}

}  // namespace
