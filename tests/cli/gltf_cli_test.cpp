// Runs rhot-demo --record and rhot-gltf, and reads the glTF back with tinygltf: the animation's
// samples are the recording's.

#include <cstring>
#include <string>

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

}  // namespace
