// Frame-capture tests on the CPU Vulkan driver (lavapipe) with the validation layer on: any
// validation message fails the test that produced it.

#include "engine/render/Renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "engine/core/Transform.h"
#include "engine/core/World.h"
#include "engine/render/SceneRenderer.h"
#include "engine/scene/SceneLoader.h"
#include "tests/support/Golden.h"
#include "tests/support/ReferenceHands.h"

namespace rhot {
namespace {

RendererSettings test_settings(int w, int h, StereoMode mode = StereoMode::kAuto) {
  RendererSettings s;
  s.eye_width_px = w;
  s.eye_height_px = h;
  s.device = "cpu";  // goldens are rendered by lavapipe, the same on every machine
  s.validation = true;
  s.stereo = mode;
  return s;
}

class RendererTest : public ::testing::Test {
 protected:
  std::unique_ptr<Renderer> make(const RendererSettings& s) {
    auto r = Renderer::create(s);
    EXPECT_TRUE(r.has_value()) << (r ? "" : r.error());
    if (!r) return nullptr;
    EXPECT_TRUE((*r)->info().validation_enabled) << "install vulkan-validationlayers (tools/setup-deps.sh)";
    EXPECT_TRUE((*r)->info().cpu_device);
    return std::move(*r);
  }
  // Counts pixels of exactly this colour (within 2 per channel).
  static int count_colour(const Image& im, glm::u8vec3 c) {
    int n = 0;
    for (std::size_t i = 0; i < im.rgba.size(); i += 4) {
      n += (std::abs(im.rgba[i] - c.r) <= 2 && std::abs(im.rgba[i + 1] - c.g) <= 2 && std::abs(im.rgba[i + 2] - c.b) <= 2) ? 1 : 0;
    }
    return n;
  }
};

#define EXPECT_NO_VALIDATION_MESSAGES(renderer) EXPECT_EQ((renderer)->validation_messages(), 0u) << "see the log above"

// A flat-coloured frame: ambient 1, no directional light, so a mesh shows exactly its colour.
FrameInput flat_frame(const StereoViews& views) {
  FrameInput f;
  f.views = views;
  f.ambient = 1.0f;
  f.light_color = glm::vec3(0.0f);
  return f;
}

TEST_F(RendererTest, UnknownDeviceIsAClearError) {
  RendererSettings s = test_settings(64, 64);
  s.device = "no-such-gpu";
  const auto r = Renderer::create(s);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().rfind("no Vulkan device matches \"no-such-gpu\" (choose auto, gpu, cpu, an index or part of a name); "
                            "devices found:",
                            0),
            0u)
      << r.error();
  s.device = "cpu";
  s.eye_width_px = 0;
  EXPECT_EQ(Renderer::create(s).error(), "eye size must be 16 to 8192 pixels each way, got 0x64");
}

// Both eyes must see about the same share of a large ground plane. Mesa 22.3.6's lavapipe drops
// geometry crossing the frustum edge from the second multiview view; the renderer's self-test
// must notice and fall back to two passes, so in auto mode both eyes always agree.
TEST_F(RendererTest, BothEyesSeeTheSameLargeGeometry) {
  HeadsetSettings headset;
  headset.eye_width_px = 160;
  headset.eye_height_px = 176;
  const StereoViews views = stereo_views(default_world_from_head(20.0f), headset);
  for (const StereoMode mode : {StereoMode::kAuto, StereoMode::kTwoPass, StereoMode::kMultiview}) {
    auto renderer = make(test_settings(160, 176, mode));
    ASSERT_NE(renderer, nullptr);
    if (mode == StereoMode::kMultiview && !renderer->info().multiview_supported) continue;
    const MeshHandle plane = renderer->upload_mesh(make_plane({40.0f, 40.0f}));
    FrameInput f = flat_frame(views);
    f.batches.push_back({plane, {{glm::mat4(1.0f), glm::vec4(0.0f, 1.0f, 0.0f, 1.0f)}}});
    renderer->render(f);
    const auto eyes = renderer->read_eyes();
    const double pixels = 160.0 * 176.0;
    const double left = count_colour(eyes[0], {0, 255, 0}) / pixels;
    const double right = count_colour(eyes[1], {0, 255, 0}) / pixels;
    EXPECT_GT(left, 0.3) << to_string(mode);
    const bool agree = std::abs(left - right) < 0.02;
    if (mode == StereoMode::kMultiview) {
      // Forced multiview: the eyes agree exactly when the self-test said the driver is right.
      EXPECT_EQ(agree, renderer->info().multiview_self_test_passed)
          << "the multiview self-test disagrees with what the driver draws: left " << left << ", right " << right;
    } else {
      EXPECT_TRUE(agree) << to_string(mode) << " (used " << to_string(renderer->info().mode) << "): left eye " << left << ", right eye "
                         << right << " of the image is ground";
    }
    EXPECT_NO_VALIDATION_MESSAGES(renderer);
  }
}

// render() returns with the frame in flight; the next render() must wait for it before reusing
// (or, when it grows, replacing) the instance buffer, and read_eyes() must show the last frame.
// Without those waits the validation layer reports a destroyed buffer still in use, or the
// picture mixes the frames.
TEST_F(RendererTest, BackToBackFramesNeverTouchTheFrameInFlight) {
  auto renderer = make(test_settings(96, 96));
  ASSERT_NE(renderer, nullptr);
  HeadsetSettings headset;
  headset.eye_width_px = headset.eye_height_px = 96;
  const StereoViews views = stereo_views(default_world_from_head(), headset);
  const MeshHandle box = renderer->upload_mesh(make_box(glm::vec3(0.01f)));
  const auto frame_of = [&](int count, glm::vec4 color) {
    FrameInput f = flat_frame(views);
    MeshBatch batch{box, {}};
    for (int i = 0; i < count; ++i) {
      const float x = -0.2f + 0.4f * static_cast<float>(i % 64) / 64.0f;
      const float y = 0.7f + 0.3f * static_cast<float>(i / 64) / 64.0f;
      batch.instances.push_back({glm::translate(glm::mat4(1.0f), {x, y, -0.6f}), color});
    }
    f.batches.push_back(std::move(batch));
    return f;
  };
  // 1, then 4096 instances (the instance buffer is replaced while the first frame may be drawn),
  // then 2 in another colour: only the last frame's colour may be in the picture.
  renderer->render(frame_of(1, glm::vec4(1, 0, 0, 1)));
  renderer->render(frame_of(4096, glm::vec4(0, 0, 1, 1)));
  renderer->render(frame_of(2, glm::vec4(0, 1, 0, 1)));
  const auto eyes = renderer->read_eyes();
  for (int eye = 0; eye < 2; ++eye) {
    EXPECT_GT(count_colour(eyes[eye], {0, 255, 0}), 0) << "eye " << eye;
    EXPECT_EQ(count_colour(eyes[eye], {255, 0, 0}), 0) << "eye " << eye;
    EXPECT_EQ(count_colour(eyes[eye], {0, 0, 255}), 0) << "eye " << eye;
  }
  renderer->render(frame_of(4096, glm::vec4(0, 0, 1, 1)));
  renderer->finish();
  EXPECT_GT(count_colour(renderer->read_eye(kLeftEye), {0, 0, 255}), 200);  // about 400
  EXPECT_NO_VALIDATION_MESSAGES(renderer);
}

// Per-pixel channel differences between two same-sized images: the count of pixels whose largest
// RGB difference exceeds each of 0, 1, 2, 4, 8, 16, 32, 64 levels, and the largest difference.
struct ChannelDiffs {
  std::array<int, 8> over{};  // over[k]: pixels differing by more than kLevels[k]
  int max = 0;
  static constexpr std::array<int, 8> kLevels{0, 1, 2, 4, 8, 16, 32, 64};
};
ChannelDiffs channel_diffs(const Image& a, const Image& b) {
  ChannelDiffs d;
  for (std::size_t i = 0; i + 3 < a.rgba.size() && i + 3 < b.rgba.size(); i += 4) {
    int m = 0;
    for (std::size_t c = 0; c < 4; ++c) m = std::max(m, std::abs(a.rgba[i + c] - b.rgba[i + c]));
    d.max = std::max(d.max, m);
    for (std::size_t k = 0; k < d.over.size(); ++k) d.over[k] += m > ChannelDiffs::kLevels[k] ? 1 : 0;
  }
  return d;
}
std::string describe(const ChannelDiffs& d, double pixels) {
  std::string s;
  for (std::size_t k = 0; k < d.over.size(); ++k) {
    s += "> " + std::to_string(ChannelDiffs::kLevels[k]) + ": " + std::to_string(100.0 * d.over[k] / pixels) + " %, ";
  }
  return s + "largest " + std::to_string(d.max);
}

// Per-vertex shading (the default on a CPU driver) lights each vertex and encodes sRGB in the
// shader; per-pixel shading lights each pixel and lets the _SRGB target encode. On flat faces,
// lines and the clear colour the two must give the same picture, within one level of rounding.
TEST_F(RendererTest, VertexAndPixelShadingAgreeOnFlatFaces) {
  HeadsetSettings headset;
  headset.eye_width_px = 200;
  headset.eye_height_px = 220;
  const StereoViews views = stereo_views(default_world_from_head(), headset);
  std::array<std::array<Image, 2>, 2> eyes;
  for (const Shading shading : {Shading::kPerPixel, Shading::kPerVertex}) {
    RendererSettings s = test_settings(200, 220);
    s.shading = shading;
    auto renderer = make(s);
    ASSERT_NE(renderer, nullptr);
    EXPECT_EQ(renderer->info().shading, shading);
    FrameInput f;
    f.views = views;
    const MeshHandle box = renderer->upload_mesh(make_box({0.12f, 0.08f, 0.1f}));
    const MeshHandle plane = renderer->upload_mesh(make_plane({1.2f, 0.8f}));
    f.batches.push_back({plane, {{glm::translate(glm::mat4(1.0f), {0.0f, 0.75f, -0.6f}), glm::vec4(0.6f, 0.45f, 0.3f, 1.0f)}}});
    MeshBatch boxes{box, {}};
    for (int i = 0; i < 12; ++i) {
      const float fi = static_cast<float>(i);
      glm::mat4 m = glm::translate(glm::mat4(1.0f), {-0.45f + 0.08f * fi, 0.82f + 0.02f * static_cast<float>(i % 3), -0.5f - 0.02f * fi});
      m = glm::rotate(m, 0.45f * fi, glm::normalize(glm::vec3(0.3f, 1.0f, 0.2f * fi)));
      boxes.instances.push_back({m, glm::vec4(0.1f + 0.07f * fi, 0.9f - 0.06f * fi, 0.5f, 1.0f)});
    }
    f.batches.push_back(std::move(boxes));
    for (int i = 0; i < 10; ++i) {
      const float x = -0.5f + 0.1f * static_cast<float>(i);
      f.lines.push_back({{x, 0.76f, -0.3f}, {0.9f, 0.2f, 0.1f, 1.0f}});
      f.lines.push_back({{x, 0.76f, -1.0f}, {0.9f, 0.2f, 0.1f, 1.0f}});
    }
    renderer->render(f);
    eyes[shading == Shading::kPerVertex ? 1 : 0] = renderer->read_eyes();
    EXPECT_NO_VALIDATION_MESSAGES(renderer);
  }
  for (int eye = 0; eye < 2; ++eye) {
    const ChannelDiffs d = channel_diffs(eyes[1][eye], eyes[0][eye]);
    EXPECT_LE(d.max, 1) << "eye " << eye << ": " << describe(d, 200.0 * 220.0);
    // The plane, boxes and lines cover a good part of the view (the top-left corner is the clear
    // colour): the comparison is not of two empty images.
    const Image& im = eyes[0][eye];
    int drawn = 0;
    for (std::size_t i = 0; i < im.rgba.size(); i += 4) {
      drawn += std::equal(im.rgba.begin() + static_cast<std::ptrdiff_t>(i), im.rgba.begin() + static_cast<std::ptrdiff_t>(i) + 3,
                          im.rgba.begin())
                   ? 0
                   : 1;
    }
    EXPECT_GT(drawn, 200 * 220 / 5) << "eye " << eye;
  }
}

// On curved surfaces per-vertex shading interpolates the diffuse term across each triangle
// (Gouraud); on the default scene, drawn at the golden's size, nearly every pixel still agrees.
TEST_F(RendererTest, VertexShadingStaysCloseToPixelShadingOnCurvedSurfaces) {
  const auto scene = load_scene_file(std::filesystem::path(RHOT_ASSET_DIR) / "scenes" / "default.json");
  ASSERT_TRUE(scene.has_value()) << scene.error().to_string();
  World world;
  instantiate(*scene, world);
  const auto hands = reference_hands();
  std::array<std::array<Image, 2>, 2> eyes;
  for (const Shading shading : {Shading::kPerPixel, Shading::kAuto}) {
    RendererSettings s = test_settings(320, 352);
    s.shading = shading;
    auto renderer = make(s);
    ASSERT_NE(renderer, nullptr);
    EXPECT_EQ(renderer->info().shading, shading == Shading::kAuto ? Shading::kPerVertex : Shading::kPerPixel)
        << "auto lights per vertex on a CPU driver";
    SceneRenderer scene_renderer(*renderer);
    renderer->render(scene_renderer.build(world, stereo_views(default_world_from_head(), scene->settings.headset), hands));
    eyes[shading == Shading::kAuto ? 1 : 0] = renderer->read_eyes();
  }
  // Measured (lavapipe, 2026-11-23): about 1.1 % of pixels more than 2 levels apart, 0.08 % more
  // than 8, at most 19 levels, on the spheres' and fingers' highlights and terminators.
  const double pixels = 320.0 * 352.0;
  for (int eye = 0; eye < 2; ++eye) {
    const ChannelDiffs d = channel_diffs(eyes[1][eye], eyes[0][eye]);
    EXPECT_LT(d.over[2], 0.03 * pixels) << "eye " << eye << ": " << describe(d, pixels);
    EXPECT_LT(d.over[4], 0.005 * pixels) << "eye " << eye << ": " << describe(d, pixels);
    EXPECT_LE(d.max, 40) << "eye " << eye << ": " << describe(d, pixels);
  }
}

// A small sphere 1 m ahead appears shifted between the eyes by f * ipd / depth pixels.
TEST_F(RendererTest, ParallaxMatchesIpdAndFocalLength) {
  constexpr int kSize = 400;
  auto renderer = make(test_settings(kSize, kSize));
  ASSERT_NE(renderer, nullptr);
  HeadsetSettings headset;
  headset.ipd_m = 0.063;
  headset.left_eye = headset.right_eye = EyeFovDeg{45, 45, 45, 45};
  const StereoViews views = stereo_views(glm::mat4(1.0f), headset);
  const MeshHandle sphere = renderer->upload_mesh(make_sphere(1.0f, 32, 16));
  for (const float depth : {0.6f, 1.0f, 2.0f}) {
    FrameInput f = flat_frame(views);
    f.batches.push_back({sphere, {{glm::scale(glm::translate(glm::mat4(1.0f), {0, 0, -depth}), glm::vec3(0.01f)), glm::vec4(1, 0, 0, 1)}}});
    renderer->render(f);
    const auto eyes = renderer->read_eyes();
    std::array<double, 2> centre_x{};
    for (int eye = 0; eye < 2; ++eye) {
      double sum = 0.0;
      int n = 0;
      const Image& im = eyes[static_cast<std::size_t>(eye)];
      for (int y = 0; y < kSize; ++y) {
        for (int x = 0; x < kSize; ++x) {
          const std::uint8_t* p = im.pixel(x, y);
          if (p[0] > 200 && p[1] < 50) {
            sum += x + 0.5;  // pixel centres
            ++n;
          }
        }
      }
      ASSERT_GT(n, 3) << "sphere not visible at depth " << depth;
      centre_x[static_cast<std::size_t>(eye)] = sum / n;
      const glm::vec2 expected = project_to_pixel(views, eye, {0, 0, -depth}, kSize, kSize);
      EXPECT_NEAR(centre_x[static_cast<std::size_t>(eye)], expected.x, 1.0) << "eye " << eye << " depth " << depth;
    }
    const double fx = (kSize / 2.0) / std::tan(M_PI / 4.0);
    EXPECT_NEAR(centre_x[0] - centre_x[1], fx * 0.063 / static_cast<double>(depth), 1.0) << "depth " << depth;
  }
  EXPECT_NO_VALIDATION_MESSAGES(renderer);
}

TEST_F(RendererTest, NonFiniteInstancesAreSkippedNotDrawn) {
  auto renderer = make(test_settings(64, 64));
  ASSERT_NE(renderer, nullptr);
  const MeshHandle box = renderer->upload_mesh(make_box(glm::vec3(1.0f)));
  HeadsetSettings headset;
  FrameInput f = flat_frame(stereo_views(glm::mat4(1.0f), headset));
  glm::mat4 bad = glm::translate(glm::mat4(1.0f), {0, 0, -3});
  bad[3][0] = std::numeric_limits<float>::quiet_NaN();
  f.batches.push_back({box, {{bad, glm::vec4(1, 0, 0, 1)}, {glm::translate(glm::mat4(1.0f), {0, 0, -3}), glm::vec4(0, 0, 1, 1)}}});
  f.lines.push_back({{0, 0, -1}, glm::vec4(1)});
  f.lines.push_back({{std::numeric_limits<float>::infinity(), 0, -1}, glm::vec4(1)});
  renderer->render(f);
  const Image left = renderer->read_eye(kLeftEye);
  EXPECT_EQ(count_colour(left, {255, 0, 0}), 0);
  EXPECT_GT(count_colour(left, {0, 0, 255}), 100) << "the finite box is still drawn";
  EXPECT_NO_VALIDATION_MESSAGES(renderer);
}

// A glTF mesh that cannot be loaded is logged and drawn as a 10 cm box in its material colour.
TEST_F(RendererTest, BrokenGltfMeshFallsBackToABox) {
  const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) / "rhot_broken_mesh.gltf";
  std::ofstream(file) << "{ not glTF";
  World world;
  const Entity e = world.create();
  world.add<Transform>(e, Transform{{0.0f, 0.0f, -0.5f}, glm::quat(1, 0, 0, 0), glm::vec3(1.0f)});
  world.add<WorldTransform>(e);
  world.add<Mesh>(e, Mesh{GltfMeshShape{file}});
  world.add<Material>(e, Material{glm::vec4(1, 0, 1, 1)});
  update_world_transforms(world);
  auto renderer = make(test_settings(64, 64));
  ASSERT_NE(renderer, nullptr);
  SceneRenderSettings no_grid;
  no_grid.draw_grid = false;
  SceneRenderer scene_renderer(*renderer, no_grid);
  HeadsetSettings headset;
  headset.left_eye = headset.right_eye = EyeFovDeg{45, 45, 45, 45};
  FrameInput f = scene_renderer.build(world, stereo_views(glm::mat4(1.0f), headset));
  f.ambient = 1.0f;
  f.light_color = glm::vec3(0.0f);
  renderer->render(f);
  // The box's front face, 0.45 m away and 0.1 m wide, covers about 64 * 0.1 / (2 * 0.45) = 7 pixels across.
  const int magenta = count_colour(renderer->read_eye(kLeftEye), {255, 0, 255});
  EXPECT_GT(magenta, 30);
  EXPECT_LT(magenta, 80);
  EXPECT_NO_VALIDATION_MESSAGES(renderer);
}

// ---- golden images ---------------------------------------------------------------------------

TEST_F(RendererTest, GoldenDefaultScene) {
  const auto scene = load_scene_file(std::filesystem::path(RHOT_ASSET_DIR) / "scenes" / "default.json");
  ASSERT_TRUE(scene.has_value()) << scene.error().to_string();
  World world;
  instantiate(*scene, world);
  // Lit per pixel: the golden predates per-vertex shading, which the test above holds to it.
  RendererSettings settings = test_settings(320, 352);
  settings.shading = Shading::kPerPixel;
  auto renderer = make(settings);
  ASSERT_NE(renderer, nullptr);
  SceneRenderer scene_renderer(*renderer);
  const auto hands = reference_hands();
  renderer->render(scene_renderer.build(world, stereo_views(default_world_from_head(), scene->settings.headset), hands));
  const auto eyes = renderer->read_eyes();
  testing::expect_matches_golden(side_by_side(eyes[0], eyes[1]), "default_scene");
  EXPECT_NO_VALIDATION_MESSAGES(renderer);
}

TEST_F(RendererTest, GoldenDebugLayer) {
  World world;
  auto renderer = make(test_settings(240, 240));
  ASSERT_NE(renderer, nullptr);
  SceneRenderer scene_renderer(*renderer);
  DebugDraw debug;
  debug.axes(glm::translate(glm::mat4(1.0f), {0.0f, 0.8f, -0.6f}), 0.15f);
  // A camera on the left looking across the volume (OpenCV frame: z forward, y down).
  glm::mat4 world_from_cam(1.0f);
  world_from_cam[0] = glm::vec4(0, 0, 1, 0);
  world_from_cam[1] = glm::vec4(0, -1, 0, 0);
  world_from_cam[2] = glm::vec4(1, 0, 0, 0);
  world_from_cam[3] = glm::vec4(-0.5f, 0.9f, -0.6f, 1);
  debug.camera_frustum(world_from_cam, 640, 480, 500, 500, 320, 240, 0.3f, glm::vec4(1, 1, 0, 1));
  debug.ray({-0.5f, 0.9f, -0.6f}, {1.0f, -0.2f, 0.1f}, 0.6f, glm::vec4(0, 1, 1, 1));
  for (int i = 0; i < 5; ++i) debug.point({-0.2f + 0.1f * static_cast<float>(i), 0.75f, -0.5f}, 0.01f, glm::vec4(1, 0, 1, 1));
  HeadsetSettings headset;
  renderer->render(scene_renderer.build(world, stereo_views(default_world_from_head(), headset), {}, &debug));
  const auto eyes = renderer->read_eyes();
  testing::expect_matches_golden(side_by_side(eyes[0], eyes[1]), "debug_layer");
  EXPECT_NO_VALIDATION_MESSAGES(renderer);
}

}  // namespace
}  // namespace rhot
