#include "engine/runtime/Overlay.h"

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

std::string Overlay::object_name(Entity e) const {
  const Name* name = demo_.world().find<Name>(e);
  return name != nullptr ? name->value : "entity " + std::to_string(e.index);
}

void Overlay::build() {
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
    ImGui::Text("t = %.2f s, frame %llu%s", demo_.time_s(), static_cast<unsigned long long>(demo_.frames()),
                demo_.paused() ? "  (paused)" : "");
    frame_panel();
    tracking_panel();
    grasp_panel();
    controls_panel();
  }
  ImGui::End();
}

void Overlay::frame_panel() {
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
  const LatencyStats& latency = demo_.latency();
  if (latency.frames() >= latency_frames_ + 45 || latency.frames() < latency_frames_) {
    latency_ = {latency.tracking(), latency.render(), latency.motion_to_photon()};
    latency_frames_ = latency.frames();
  }
  ImGui::Text("latency p50 / p99: tracking %.1f / %.1f ms, render %.1f / %.1f ms", latency_[0].p50_ms, latency_[0].p99_ms,
              latency_[1].p50_ms, latency_[1].p99_ms);
  ImGui::Text("motion-to-photon %.1f / %.1f ms (hands drawn %s)", latency_[2].p50_ms, latency_[2].p99_ms,
              demo_.predicting() ? "at display time" : "as tracked");
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

void Overlay::tracking_panel() {
  if (!ImGui::CollapsingHeader("Tracking", ImGuiTreeNodeFlags_DefaultOpen)) return;
  ResultSource& tracking = demo_.tracking();
  const TrackingCounts& c = tracking.results().counts;
  if (const CameraRig* rig = tracking.rig()) {
    std::string per_camera;
    for (const std::size_t n : c.detections_per_camera) per_camera += (per_camera.empty() ? "" : " ") + std::to_string(n);
    ImGui::Text("%zu cameras, detections: %s", rig->cameras.size(), per_camera.c_str());
    if (!c.cameras_without_frame.empty()) {
      std::string missing;
      for (const int cam : c.cameras_without_frame) missing += (missing.empty() ? "" : ", ") + std::to_string(cam);
      ImGui::TextColored(ImVec4(1.0f, 0.55f, 0.2f, 1.0f), "no frame from camera %s (node lost or late)", missing.c_str());
    }
    ImGui::Text("%zu points, reprojection RMS %.2f px", c.points, c.mean_reprojection_rms_px);
  } else {
    ImGui::TextUnformatted(tracking.playback() ? "playing back a recording: no cameras" : "no cameras");
  }
  std::string stars;
  for (const int id : c.seen_star_ids) stars += (stars.empty() ? "" : ", ") + std::to_string(id);
  ImGui::Text("marker stars identified: %d%s%s", c.stars_seen, stars.empty() ? "" : "  (", stars.empty() ? "" : (stars + ")").c_str());
  for (const HandSide side : {HandSide::kLeft, HandSide::kRight}) {
    const Hand& hand = demo_.hand(side);
    const HandInput& in = hand.tracked;
    if (!in.seen) {
      ImGui::Text("%s hand: not seen", side_name(side));
      continue;
    }
    const double confidence = std::accumulate(in.confidence.begin(), in.confidence.end(), 0.0) / static_cast<double>(in.confidence.size());
    ImGui::Text("%s hand: confidence %.2f", side_name(side), confidence);
    if (hand.gestures_measured) {
      ImGui::SameLine();
      ImGui::Text(" pinch %.2f%s  grip %.2f%s", hand.pinch.activation, hand.pinch.active ? " (on)" : "", hand.grip.activation,
                  hand.grip.active ? " (on)" : "");
    }
  }
}

void Overlay::grasp_panel() {
  if (!ImGui::CollapsingHeader("Grasp", ImGuiTreeNodeFlags_DefaultOpen)) return;
  HandPhysics& physics = demo_.physics();
  for (const HandSide side : {HandSide::kLeft, HandSide::kRight}) {
    const auto held = physics.grasp().holding(side);
    ImGui::Text("%s hand holds: %s", side_name(side), held ? object_name(*held).c_str() : "nothing");
    // Each fingertip's confidence, and which hidden ones rest on an object (FingerContact.h).
    const HandInput& tracked = demo_.hand(side).tracked;
    if (!tracked.seen) continue;
    const FingerPlacement& placed = physics.placements()[side == HandSide::kLeft ? 0 : 1];
    static constexpr std::array<HandJoint, 5> kTips{HandJoint::kThumbTip, HandJoint::kIndexTip, HandJoint::kMiddleTip, HandJoint::kRingTip,
                                                    HandJoint::kLittleTip};
    static constexpr std::array<const char*, 5> kDigits{"T", "I", "M", "R", "L"};
    std::string line = "  tips:";
    for (std::size_t d = 0; d < 5; ++d) {
      char one[32];
      std::snprintf(one, sizeof(one), " %s %.2f%s", kDigits[d], tracked.confidence[static_cast<std::size_t>(kTips[d])],
                    placed.placed[d] ? " (on object)" : "");
      line += one;
    }
    ImGui::TextUnformatted(line.c_str());
  }
  // This frame's events, once per frame the demo ran.
  if (events_frame_ != demo_.frames()) {
    events_frame_ = demo_.frames();
    for (const InteractionEvent& e : physics.events()) {
      if (e.type == InteractionEventType::kHoverBegin || e.type == InteractionEventType::kHoverEnd) continue;
      char line[256];
      std::snprintf(line, sizeof(line), "%6.2f s  %s %s%s%s%s%s", e.time_s, event_name(e.type), object_name(e.object).c_str(),
                    e.hand ? " by the " : "", e.hand ? side_name(*e.hand) : "", e.reason.empty() ? "" : ": ", e.reason.c_str());
      events_.emplace_front(line);
      if (events_.size() > kEventLines) events_.pop_back();
    }
  }
  for (const std::string& line : events_) ImGui::TextUnformatted(line.c_str());
}

void Overlay::controls_panel() {
  if (!ImGui::CollapsingHeader("Controls", ImGuiTreeNodeFlags_DefaultOpen)) return;
  if (ImGui::Button(demo_.paused() ? "Resume (Space)" : "Pause (Space)")) demo_.set_paused(!demo_.paused());
  ImGui::SameLine();
  if (!demo_.paused()) ImGui::BeginDisabled();
  if (ImGui::Button("Step (Right)")) demo_.step();
  if (!demo_.paused()) ImGui::EndDisabled();
  if (Playback* playback = demo_.tracking().playback()) {
    auto speed = static_cast<float>(playback->speed());
    if (ImGui::SliderFloat("speed", &speed, 0.05f, 4.0f, "%.2f x", ImGuiSliderFlags_Logarithmic))
      playback->set_speed(std::clamp(static_cast<double>(speed), 0.05, 4.0));
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
