// rhot-gltf: a recording (rhot-demo --record) as a glTF 2.0 file with animated nodes, to open in
// Blender or any glTF viewer: a node per hand joint (a small octahedron, "left_index_tip" ...) and
// per tracked object (named as in the scene, a small axis-aligned box), one animation with their
// translations (and the objects' rotations) at the recording's times, linearly interpolated.
// Frames where a hand was not seen keep its joints where they were last seen.
// With --format bvh: the hands as a BVH skeleton with rotation channels per joint (Bvh.h).

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

// GCC 12 at -O2 reports a null dereference inside CLI11's option parsing (a false positive in
// libstdc++'s string move); the pragma covers only CLI11's lines.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <CLI/CLI.hpp>
#pragma GCC diagnostic pop
#include <tiny_gltf.h>

#include "engine/tracked/Recording.h"
#include "tools/gltf/Bvh.h"
#include "tools/common/CliExit.h"
#include "tools/common/NumberChecks.h"

namespace {

// Appends raw floats to the buffer and returns the accessor index.
int add_floats(tinygltf::Model& m, const std::vector<float>& data, int components, bool min_max) {
  tinygltf::Buffer& buffer = m.buffers[0];
  const std::size_t offset = buffer.data.size();
  buffer.data.resize(offset + data.size() * sizeof(float));
  std::memcpy(buffer.data.data() + offset, data.data(), data.size() * sizeof(float));
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = offset;
  view.byteLength = data.size() * sizeof(float);
  m.bufferViews.push_back(view);
  tinygltf::Accessor a;
  a.bufferView = static_cast<int>(m.bufferViews.size()) - 1;
  a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  a.count = data.size() / static_cast<std::size_t>(components);
  a.type = components == 1 ? TINYGLTF_TYPE_SCALAR : components == 3 ? TINYGLTF_TYPE_VEC3 : TINYGLTF_TYPE_VEC4;
  if (min_max) {
    a.minValues.assign(static_cast<std::size_t>(components), 1e30);
    a.maxValues.assign(static_cast<std::size_t>(components), -1e30);
    for (std::size_t i = 0; i < data.size(); ++i) {
      const auto c = i % static_cast<std::size_t>(components);
      a.minValues[c] = std::min(a.minValues[c], static_cast<double>(data[i]));
      a.maxValues[c] = std::max(a.maxValues[c], static_cast<double>(data[i]));
    }
  }
  m.accessors.push_back(a);
  return static_cast<int>(m.accessors.size()) - 1;
}

// A closed mesh (octahedron or box) of half size h, positions only.
int add_mesh(tinygltf::Model& m, const std::string& name, float h, bool box) {
  std::vector<float> positions;
  std::vector<int> tris;
  if (box) {
    for (int i = 0; i < 8; ++i) {
      positions.insert(positions.end(), {(i & 4 ? h : -h), (i & 2 ? h : -h), (i & 1 ? h : -h)});
    }
    tris = {0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1, 2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3};
  } else {
    positions = {h, 0, 0, -h, 0, 0, 0, h, 0, 0, -h, 0, 0, 0, h, 0, 0, -h};
    tris = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  }
  const int pos = add_floats(m, positions, 3, true);
  tinygltf::Buffer& buffer = m.buffers[0];
  const std::size_t offset = buffer.data.size();
  for (const int i : tris) {
    const auto v = static_cast<std::uint16_t>(i);
    buffer.data.push_back(static_cast<unsigned char>(v & 0xff));
    buffer.data.push_back(static_cast<unsigned char>(v >> 8));
  }
  while (buffer.data.size() % 4) buffer.data.push_back(0);
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = offset;
  view.byteLength = tris.size() * 2;
  view.target = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;
  m.bufferViews.push_back(view);
  tinygltf::Accessor a;
  a.bufferView = static_cast<int>(m.bufferViews.size()) - 1;
  a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
  a.count = tris.size();
  a.type = TINYGLTF_TYPE_SCALAR;
  m.accessors.push_back(a);
  tinygltf::Primitive p;
  p.attributes["POSITION"] = pos;
  p.indices = static_cast<int>(m.accessors.size()) - 1;
  p.mode = TINYGLTF_MODE_TRIANGLES;
  tinygltf::Mesh mesh;
  mesh.name = name;
  mesh.primitives.push_back(p);
  m.meshes.push_back(mesh);
  return static_cast<int>(m.meshes.size()) - 1;
}

// The recording's hands as BVH in `output`: the exit status, after saying what went wrong.
int write_bvh(const rhot::Recording& rec, const std::string& input, const std::string& output, const std::string& bvh_unit) {
  const auto text = rhot::hands_bvh(rec, {bvh_unit == "cm" ? 100.0 : 1.0});
  if (!text) {
    std::cerr << "rhot-gltf: " << input << ": " << text.error() << "\n";
    return 1;
  }
  std::ofstream out(output);
  out << *text;
  out.close();
  if (!out) {
    std::cerr << "rhot-gltf: cannot write " << output << "\n";
    return 1;
  }
  std::cerr << "rhot-gltf: " << rec.frames.size() << " frames of both hands at " << rec.rate_hz << " Hz written to " << output << " (BVH, "
            << bvh_unit << ")\n";
  return 0;
}

// The animation of a glTF file being built: one sampler and channel per animated property, all
// keyed at the recording's frame times.
struct Animating {
  tinygltf::Model& m;
  tinygltf::Scene& scene;
  tinygltf::Animation& animation;
  int time_accessor;

  // A new node of the scene showing `mesh`: its index.
  int add_node(const std::string& name, int mesh) {
    tinygltf::Node node;
    node.name = name;
    node.mesh = mesh;
    m.nodes.push_back(node);
    const int index = static_cast<int>(m.nodes.size()) - 1;
    scene.nodes.push_back(index);
    return index;
  }
  // path: "translation" (3 components per frame) or "rotation" (4: x, y, z, w).
  void animate(int node, const std::string& path, const std::vector<float>& values, int components) {
    tinygltf::AnimationSampler sampler;
    sampler.input = time_accessor;
    sampler.output = add_floats(m, values, components, false);
    sampler.interpolation = "LINEAR";
    animation.samplers.push_back(sampler);
    tinygltf::AnimationChannel channel;
    channel.sampler = static_cast<int>(animation.samplers.size()) - 1;
    channel.target_node = node;
    channel.target_path = path;
    animation.channels.push_back(channel);
  }
};

// A node per joint of both hands, where it was last seen.
void add_hand_nodes(Animating& gltf, const rhot::Recording& rec, int joint_mesh) {
  for (std::size_t h = 0; h < 2; ++h) {
    for (int j = 0; j < rhot::kHandJointCount; ++j) {
      const int index = gltf.add_node(
          std::string(h == 0 ? "left_" : "right_") + std::string(rhot::joint_name(static_cast<rhot::HandJoint>(j))), joint_mesh);
      std::vector<float> t;
      Eigen::Vector3d last = Eigen::Vector3d::Zero();
      for (const auto& f : rec.frames) {
        if (f.hands[h].seen) last = f.hands[h].joints_world[static_cast<std::size_t>(j)];
        t.insert(t.end(), {static_cast<float>(last.x()), static_cast<float>(last.y()), static_cast<float>(last.z())});
      }
      gltf.animate(index, "translation", t, 3);
    }
  }
}

// A node per tracked object, where it was last tracked.
void add_object_nodes(Animating& gltf, const rhot::Recording& rec, int object_mesh) {
  for (const std::string& name : rec.objects) {
    const int index = gltf.add_node(name, object_mesh);
    std::vector<float> t, r;
    rhot::Rigid3d last;
    for (const auto& f : rec.frames) {
      if (const auto it = f.objects.find(name); it != f.objects.end()) last = it->second;
      t.insert(t.end(), {static_cast<float>(last.translation.x()), static_cast<float>(last.translation.y()),
                         static_cast<float>(last.translation.z())});
      r.insert(r.end(), {static_cast<float>(last.rotation.x()), static_cast<float>(last.rotation.y()),
                         static_cast<float>(last.rotation.z()), static_cast<float>(last.rotation.w())});
    }
    gltf.animate(index, "translation", t, 3);
    gltf.animate(index, "rotation", r, 4);
  }
}

// The recording as glTF with animated nodes in `output`: the exit status, after saying what went
// wrong.
int write_gltf(const rhot::Recording& rec, const std::string& output, double joint_mm) {
  tinygltf::Model m;
  m.asset.version = "2.0";
  m.asset.generator = "rhot-gltf";
  m.buffers.emplace_back();
  tinygltf::Scene scene;
  scene.name = "recording";
  const int joint_mesh = add_mesh(m, "joint", static_cast<float>(0.5e-3 * joint_mm), false);
  const int object_mesh = add_mesh(m, "object", 0.02f, true);

  std::vector<float> times;
  for (const auto& f : rec.frames) times.push_back(static_cast<float>(f.t_s - rec.frames.front().t_s));
  const int time_accessor = add_floats(m, times, 1, true);
  tinygltf::Animation animation;
  animation.name = "recording";
  Animating gltf{m, scene, animation, time_accessor};
  add_hand_nodes(gltf, rec, joint_mesh);
  add_object_nodes(gltf, rec, object_mesh);
  m.animations.push_back(animation);
  m.scenes.push_back(scene);
  m.defaultScene = 0;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToFile(&m, output, true, true, true, false)) {
    std::cerr << "rhot-gltf: cannot write " << output << "\n";
    return 1;
  }
  std::cerr << "rhot-gltf: " << rec.frames.size() << " frames, " << scene.nodes.size() << " animated nodes written to " << output << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"rhot-gltf: a rhot recording as a glTF 2.0 file with animated nodes (hand joints and tracked objects), or its hands as BVH"};
  std::string input, output, format = "gltf", bvh_unit = "cm";
  double joint_mm = 8.0;
  cli.add_option("recording", input, "recording (rhot-demo --record FILE)")->required();
  cli.add_option("--out", output, "file to write (.gltf with buffers embedded, or .bvh)")->required();
  cli.add_option("--format", format, "gltf: animated nodes; bvh: the hands as a skeleton with rotation channels")
      ->capture_default_str()
      ->check(CLI::IsMember({"gltf", "bvh"}));
  cli.add_option("--bvh-unit", bvh_unit, "unit of the BVH file's lengths")->capture_default_str()->check(CLI::IsMember({"cm", "m"}));
  cli.add_option("--joint-size-mm", joint_mm, "size of each joint's marker shape (glTF)")
      ->capture_default_str()
      ->check(rhot::number_check(rhot::NumberBound::kPositive))  // CLI::Range lets nan through, into the mesh
      ->check(CLI::Range(0.1, 100.0));
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return rhot::cli_exit_status(cli, e);
  }

  const auto rec = rhot::load_recording(input);
  if (!rec) {
    std::cerr << "rhot-gltf: " << rec.error() << "\n";
    return 1;
  }
  if (format == "bvh") return write_bvh(*rec, input, output, bvh_unit);
  return write_gltf(*rec, output, joint_mm);
}
