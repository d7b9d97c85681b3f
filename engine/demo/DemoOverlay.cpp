#include "engine/demo/DemoOverlay.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <numeric>

#include <imgui.h>

#include "engine/scene/Components.h"

namespace rhot {

namespace {

constexpr std::size_t kGraphFrames = 270;  // 3 s at 90 Hz
constexpr std::size_t kEventLines = 6;

const char* side_name(HandSide side) { return side == HandSide::kLeft ? "left" : "right"; }

}  // namespace

std::string DemoOverlay::object_name(Entity e) const {
  const Name* name = demo_.world().find<Name>(e);
  return name != nullptr ? name->value : "entity " + std::to_string(e.index);
}

void DemoOverlay::build() {
  const ImGuiIO& io = ImGui::GetIO();
  if (!io.WantCaptureKeyboard) {
    if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Space), false)) demo_.set_paused(!demo_.paused());
    if (demo_.paused() && (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_RightArrow)) || ImGui::IsKeyPressed('N'))) demo_.step();
  }
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(380, 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSizeConstraints(ImVec2(200, 100), ImVec2(io.DisplaySize.x, std::max(100.0f, io.DisplaySize.y - 16.0f)));
  ImGui::SetNextWindowBgAlpha(0.85f);
  if (ImGui::Begin("rhot")) {
    ImGui::Text("%s  |  %s", info_.source.c_str(), std::filesystem::path(info_.scene).filename().c_str());
    ImGui::Text("%s, %d x %d per eye", info_.device.c_str(), info_.eye_width_px, info_.eye_height_px);
    ImGui::Text("t = %.2f s, frame %llu%s", demo_.demo_time_s(), static_cast<unsigned long long>(demo_.demo_frames()),
                demo_.paused() ? "  (paused)" : "");
    frame_panel();
    tracking_panel();
    grasp_panel();
    controls_panel();
  }
  ImGui::End();
}

void DemoOverlay::frame_panel() {
  if (!ImGui::CollapsingHeader("Frame time", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const std::vector<double> recent = stats_.recent_frame_ms(kGraphFrames);
  std::vector<float> values(recent.begin(), recent.end());
  const auto budget = static_cast<float>(stats_.budget_ms());
  // Twice the budget, or more where recent frames took longer, so every frame stays on the graph.
  const float slowest = values.empty() ? 0.0f : *std::max_element(values.begin(), values.end());
  const float top = std::max(2.0f * budget, 1.1f * slowest);
  const TimingSummary whole = stats_.frame_summary();
  // One bar per frame, green within the budget and red over it; the budget as a line across.
  const ImVec2 lo = ImGui::GetCursorScreenPos();
  const float width = std::max(100.0f, ImGui::GetContentRegionAvail().x);
  const float height = 70.0f;
  ImGui::Dummy(ImVec2(width, height));
  const ImVec2 hi(lo.x + width, lo.y + height);
  ImDrawList* draw = ImGui::GetWindowDrawList();
  draw->AddRectFilled(lo, hi, IM_COL32(20, 24, 32, 220));
  const float bar = width / static_cast<float>(kGraphFrames);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const float x = hi.x - bar * static_cast<float>(values.size() - i);
    const float y = hi.y - height * std::min(1.0f, values[i] / top);
    draw->AddRectFilled(ImVec2(x, y), ImVec2(x + std::max(1.0f, bar), hi.y),
                        values[i] > budget ? IM_COL32(230, 80, 70, 255) : IM_COL32(90, 200, 110, 255));
  }
  const float budget_y = hi.y - height * (budget / top);
  draw->AddLine(ImVec2(lo.x, budget_y), ImVec2(hi.x, budget_y), IM_COL32(255, 220, 90, 255), 1.5f);
  char label[96];
  std::snprintf(label, sizeof(label), "%.0f ms", static_cast<double>(top));
  draw->AddText(ImVec2(lo.x + 3, lo.y + 1), IM_COL32(220, 220, 220, 255), label);
  ImGui::Text("whole frame: p50 %.2f ms, p99 %.2f ms", whole.p50_ms, whole.p99_ms);
  const std::uint64_t frames = stats_.frames();
  const double misses = frames == 0 ? 0.0 : 100.0 * static_cast<double>(stats_.frames_over_budget()) / static_cast<double>(frames);
  ImGui::Text("budget %.1f ms (yellow line): %llu of %llu over (%.2f %%)", stats_.budget_ms(),
              static_cast<unsigned long long>(stats_.frames_over_budget()), static_cast<unsigned long long>(frames), misses);
  if (ImGui::BeginTable("stages", 4, ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingStretchProp)) {
    ImGui::TableSetupColumn("stage");
    ImGui::TableSetupColumn("last ms");
    ImGui::TableSetupColumn("p50 ms");
    ImGui::TableSetupColumn("p99 ms");
    ImGui::TableHeadersRow();
    for (std::size_t i = 0; i < stats_.stage_names().size(); ++i) {
      const TimingSummary s = stats_.stage_summary(i);
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(stats_.stage_names()[i].c_str());
      ImGui::TableNextColumn();
      ImGui::Text("%.3f", stats_.last_stage_ms(i));
      ImGui::TableNextColumn();
      ImGui::Text("%.3f", s.p50_ms);
      ImGui::TableNextColumn();
      ImGui::Text("%.3f", s.p99_ms);
    }
    ImGui::EndTable();
  }
}

void DemoOverlay::tracking_panel() {
  if (!ImGui::CollapsingHeader("Tracking", ImGuiTreeNodeFlags_DefaultOpen)) return;
  Pipeline& p = demo_.pipeline();
  const PipelineCounts& c = p.counts();
  if (p.replaying()) {
    ImGui::TextUnformatted("replaying a recording: no cameras");
  } else {
    std::string per_camera;
    for (const CameraFrame& cam : p.frame().cameras) {
      per_camera += (per_camera.empty() ? "" : " ") + std::to_string(cam.detections.size());
    }
    ImGui::Text("%zu cameras, detections: %s", p.rig().cameras.size(), per_camera.c_str());
    ImGui::Text("%zu points, reprojection RMS %.2f px", c.points, c.mean_reprojection_rms_px);
  }
  std::string stars;
  for (const int id : c.seen_star_ids) stars += (stars.empty() ? "" : ", ") + std::to_string(id);
  ImGui::Text("marker stars identified: %d%s%s", c.stars_seen, stars.empty() ? "" : "  (", stars.empty() ? "" : (stars + ")").c_str());
  for (const HandSide side : {HandSide::kLeft, HandSide::kRight}) {
    const HandInput& in = p.hand_inputs()[side == HandSide::kLeft ? 0 : 1];
    if (!in.seen) {
      ImGui::Text("%s hand: not seen", side_name(side));
      continue;
    }
    const double confidence = std::accumulate(in.confidence.begin(), in.confidence.end(), 0.0) / static_cast<double>(in.confidence.size());
    ImGui::Text("%s hand: confidence %.2f", side_name(side), confidence);
    if (!p.replaying()) {
      const HandState& state = p.tracked_hand(side).state;
      ImGui::SameLine();
      ImGui::Text(" pinch %.2f%s  grip %.2f%s", state.pinch.activation, state.pinch.active ? " (on)" : "", state.grip.activation,
                  state.grip.active ? " (on)" : "");
    }
  }
}

void DemoOverlay::grasp_panel() {
  if (!ImGui::CollapsingHeader("Grasp", ImGuiTreeNodeFlags_DefaultOpen)) return;
  HandPhysics& physics = demo_.pipeline().hand_physics();
  for (const HandSide side : {HandSide::kLeft, HandSide::kRight}) {
    const auto held = physics.grasp().holding(side);
    ImGui::Text("%s hand holds: %s", side_name(side), held ? object_name(*held).c_str() : "nothing");
  }
  // This frame's events, once per frame the demo ran.
  if (events_frame_ != demo_.demo_frames()) {
    events_frame_ = demo_.demo_frames();
    for (const InteractionEvent& e : physics.events()) {
      if (e.type == InteractionEventType::kHoverBegin || e.type == InteractionEventType::kHoverEnd) continue;
      char line[160];
      std::snprintf(line, sizeof(line), "%6.2f s  %s %s%s%s", e.time_s, event_name(e.type), object_name(e.object).c_str(),
                    e.hand ? " by the " : "", e.hand ? side_name(*e.hand) : "");
      events_.emplace_front(line);
      if (events_.size() > kEventLines) events_.pop_back();
    }
  }
  for (const std::string& line : events_) ImGui::TextUnformatted(line.c_str());
}

void DemoOverlay::controls_panel() {
  if (!ImGui::CollapsingHeader("Controls", ImGuiTreeNodeFlags_DefaultOpen)) return;
  if (ImGui::Button(demo_.paused() ? "Resume (Space)" : "Pause (Space)")) demo_.set_paused(!demo_.paused());
  ImGui::SameLine();
  if (!demo_.paused()) ImGui::BeginDisabled();
  if (ImGui::Button("Step (Right)")) demo_.step();
  if (!demo_.paused()) ImGui::EndDisabled();
  Pipeline& p = demo_.pipeline();
  if (p.replaying()) {
    auto speed = static_cast<float>(p.speed());
    if (ImGui::SliderFloat("speed", &speed, 0.05f, 4.0f, "%.2f x", ImGuiSliderFlags_Logarithmic))
      p.set_speed(std::clamp(static_cast<double>(speed), 0.05, 4.0));
  }
  DebugViews& v = demo_.debug_views();
  ImGui::Checkbox("markers", &v.markers);
  ImGui::SameLine();
  ImGui::Checkbox("rays", &v.rays);
  ImGui::SameLine();
  ImGui::Checkbox("frusta", &v.frusta);
  ImGui::SameLine();
  ImGui::Checkbox("colliders", &v.colliders);
}

}  // namespace rhot
