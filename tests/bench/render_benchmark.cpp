// Stereo rendering cost: the default scene (table, 13 objects, two hands, ground grid) and 500
// lit cubes, drawn for both eyes and waited for (submit to fence), with multiview and with one
// pass per eye, lit per pixel and per vertex (the renderer's "auto" picks per vertex on a CPU
// driver); and the cost of reading a frame back. Each benchmark reports p50_ms and p99_ms
// over its frames. Results: docs/PERFORMANCE.md.
//
// The device is "auto" (a GPU where there is one) unless RHOT_VK_DEVICE says otherwise.

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <vector>

#include <benchmark/benchmark.h>
#include <glm/gtc/matrix_transform.hpp>
#include <spdlog/spdlog.h>

#include "engine/app/FrameStats.h"
#include "tests/support/ReferenceHands.h"
#include "engine/core/World.h"
#include "engine/render/Renderer.h"
#include "engine/render/SceneRenderer.h"
#include "engine/scene/SceneLoader.h"

namespace {

using Clock = std::chrono::steady_clock;

std::unique_ptr<rhot::Renderer> make_renderer(benchmark::State& state, rhot::StereoMode mode,
                                              rhot::Shading shading = rhot::Shading::kAuto) {
  spdlog::set_level(spdlog::level::warn);
  rhot::RendererSettings s;
  s.eye_width_px = static_cast<int>(state.range(0));
  s.eye_height_px = static_cast<int>(state.range(1));
  s.stereo = mode;
  s.shading = shading;
  auto r = rhot::Renderer::create(s);
  if (!r) {
    state.SkipWithError(r.error().c_str());
    return nullptr;
  }
  state.SetLabel((*r)->info().device_name + ", " + rhot::to_string((*r)->info().mode) + ", lit per " +
                 rhot::to_string((*r)->info().shading));
  return std::move(*r);
}

void report(benchmark::State& state, const std::vector<double>& ms) {
  state.counters["p50_ms"] = rhot::percentile(ms, 0.50);
  state.counters["p99_ms"] = rhot::percentile(ms, 0.99);
  state.counters["frames"] = static_cast<double>(ms.size());
}

rhot::FrameInput default_scene_frame(rhot::Renderer& renderer, rhot::World& world, rhot::SceneRenderer& scene_renderer) {
  const auto scene = rhot::load_scene_file(std::filesystem::path(RHOT_ASSET_DIR) / "scenes" / "default.json");
  if (!scene) return {};
  rhot::instantiate(*scene, world);
  const auto hands = rhot::reference_hands();
  (void)renderer;
  return scene_renderer.build(world, rhot::stereo_views(rhot::default_world_from_head(), scene->settings.headset), hands);
}

rhot::FrameInput cubes_frame(rhot::Renderer& renderer, int count) {
  rhot::FrameInput f;
  rhot::HeadsetSettings headset;
  f.views = rhot::stereo_views(rhot::default_world_from_head(), headset);
  rhot::MeshBatch batch{renderer.upload_mesh(rhot::make_box(glm::vec3(0.05f))), {}};
  for (int i = 0; i < count; ++i) {
    const float x = -0.5f + 0.05f * static_cast<float>(i % 20);
    const float z = -0.3f - 0.05f * static_cast<float>((i / 20) % 25);
    const glm::mat4 m = glm::rotate(glm::translate(glm::mat4(1.0f), {x, 0.8f, z}), 0.1f * static_cast<float>(i), {0, 1, 0});
    batch.instances.push_back({m, glm::vec4(0.2f + 0.6f * static_cast<float>(i % 7) / 7.0f, 0.5f, 0.7f, 1.0f)});
  }
  f.batches.push_back(std::move(batch));
  return f;
}

void run_frames(benchmark::State& state, rhot::Renderer& renderer, const rhot::FrameInput& frame, bool read_back) {
  std::vector<double> ms;
  for (auto _ : state) {
    const auto start = Clock::now();
    renderer.render(frame);
    if (read_back) benchmark::DoNotOptimize(renderer.read_eyes());
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
  report(state, ms);
}

void BM_DefaultScene(benchmark::State& state, rhot::StereoMode mode, rhot::Shading shading) {
  auto renderer = make_renderer(state, mode, shading);
  if (!renderer) return;
  rhot::World world;
  rhot::SceneRenderer scene_renderer(*renderer);
  const rhot::FrameInput frame = default_scene_frame(*renderer, world, scene_renderer);
  run_frames(state, *renderer, frame, false);
}

void BM_Cubes500(benchmark::State& state, rhot::StereoMode mode, rhot::Shading shading) {
  auto renderer = make_renderer(state, mode, shading);
  if (!renderer) return;
  run_frames(state, *renderer, cubes_frame(*renderer, 500), false);
}

// Nothing drawn: clearing and storing both eyes' colour and depth, submitting and waiting. The
// floor under every frame at that size; BM_DefaultScene minus this is what the scene's triangles
// cost.
void BM_EmptyFrame(benchmark::State& state, rhot::StereoMode mode) {
  auto renderer = make_renderer(state, mode);
  if (!renderer) return;
  rhot::FrameInput frame;
  rhot::HeadsetSettings headset;
  frame.views = rhot::stereo_views(rhot::default_world_from_head(), headset);
  run_frames(state, *renderer, frame, false);
}

// Render plus copying both eyes to the CPU, as --capture does; subtract BM_DefaultScene.
void BM_DefaultSceneWithReadBack(benchmark::State& state) {
  auto renderer = make_renderer(state, rhot::StereoMode::kAuto);
  if (!renderer) return;
  rhot::World world;
  rhot::SceneRenderer scene_renderer(*renderer);
  run_frames(state, *renderer, default_scene_frame(*renderer, world, scene_renderer), true);
}

// Building the frame from the ECS (CPU only): what the render system costs before the GPU starts.
void BM_BuildFrameFromWorld(benchmark::State& state) {
  auto renderer = make_renderer(state, rhot::StereoMode::kAuto);
  if (!renderer) return;
  rhot::World world;
  rhot::SceneRenderer scene_renderer(*renderer);
  (void)default_scene_frame(*renderer, world, scene_renderer);
  const auto hands = rhot::reference_hands();
  rhot::HeadsetSettings headset;
  const auto views = rhot::stereo_views(rhot::default_world_from_head(), headset);
  for (auto _ : state) benchmark::DoNotOptimize(scene_renderer.build(world, views, hands));
}

void sizes(benchmark::internal::Benchmark* b) {
  // Wall time: the calling thread mostly waits on the fence while the driver works.
  b->Args({1080, 1200})->Args({720, 800})->Args({540, 600})->Args({432, 480})->Args({64, 64})->Unit(benchmark::kMillisecond)->UseRealTime();
}

using rhot::Shading;
using rhot::StereoMode;
BENCHMARK_CAPTURE(BM_DefaultScene, multiview, StereoMode::kMultiview, Shading::kAuto)->Apply(sizes);
BENCHMARK_CAPTURE(BM_DefaultScene, two_pass, StereoMode::kTwoPass, Shading::kAuto)->Apply(sizes);
BENCHMARK_CAPTURE(BM_DefaultScene, two_pass_pixel_lit, StereoMode::kTwoPass, Shading::kPerPixel)->Apply(sizes);
BENCHMARK_CAPTURE(BM_DefaultScene, two_pass_vertex_lit, StereoMode::kTwoPass, Shading::kPerVertex)->Apply(sizes);
BENCHMARK_CAPTURE(BM_Cubes500, multiview, StereoMode::kMultiview, Shading::kAuto)->Apply(sizes);
BENCHMARK_CAPTURE(BM_Cubes500, two_pass, StereoMode::kTwoPass, Shading::kAuto)->Apply(sizes);
BENCHMARK_CAPTURE(BM_Cubes500, two_pass_pixel_lit, StereoMode::kTwoPass, Shading::kPerPixel)->Apply(sizes);
BENCHMARK_CAPTURE(BM_Cubes500, two_pass_vertex_lit, StereoMode::kTwoPass, Shading::kPerVertex)->Apply(sizes);
BENCHMARK(BM_DefaultSceneWithReadBack)->Apply(sizes);
BENCHMARK_CAPTURE(BM_EmptyFrame, two_pass, rhot::StereoMode::kTwoPass)->Apply(sizes);
BENCHMARK(BM_BuildFrameFromWorld)->Args({1080, 1200})->Unit(benchmark::kMicrosecond);

}  // namespace
