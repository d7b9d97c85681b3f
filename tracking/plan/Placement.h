#pragma once
// Placing cameras of one model around a volume so that as much of it as possible is seen by
// enough cameras, with as little predicted error as possible.
//
// Mounting (the world is rhot's: metres, +Y up, the floor at Y = 0):
// - ceiling: cameras at the ceiling's height, anywhere over the volume's footprint widened by
//   `wall_margin_m` on every side, looking straight down or tilted towards points of the volume;
// - walls: cameras on the four walls, which stand `wall_margin_m` outside the volume's sides, at
//   heights from the volume's top to the ceiling, looking at points of the volume.
// Every candidate looks at the volume (its centre, the centres of its quarters, or straight down
// onto it), so no planned camera looks at nothing.
//
// The search: candidate poses on the mounts (one camera a place), each camera's visibility and
// Fisher information (J^T J) at every point of a coarse lattice through the volume (face to face:
// corners and edges included) computed once; cameras added greedily, each the candidate that
// raises the score most; the set improved by swapping one camera at a time for a better candidate
// until no swap helps; then each camera moved where the worst point's predicted error falls most,
// keeping as many points seen by two as before and coverage by K within 1 % of the volume. The score
// over the lattice's points:
//     min(views, K) / K  +  0.5 [views >= 2]  -  0.1 ln(1 + rms_error / ref)   (last: views >= 2)
// so coverage by K cameras comes first, coverage by two next, and the predicted error (Cramer-Rao
// at sigma_px, Coverage.h) decides between layouts that cover alike; ref is the error of one
// pixel's noise at the volume's size from a single camera. docs/planning.md has the details.

#include <expected>
#include <functional>
#include <string>

#include "tracking/camera/Camera.h"
#include "tracking/plan/Coverage.h"

namespace rhot {

enum class Mount { kCeiling, kWalls, kBoth };

struct PlanSettings {
  Mount mount = Mount::kBoth;
  int cameras = 0;            // how many to place; 0: as few as reach max_error_mm
  double max_error_mm = 0.0;  // with cameras == 0: the worst point's predicted error (Coverage.h's
                              // predicted_max_mm) to reach, with 99 % of the volume seen by min_views
  int min_views = 3;          // K
  double sigma_px = 0.3;
  double ceiling_m = 0.0;  // the ceiling mount's height; 0: the volume's top plus 1 m
  double wall_margin_m = 0.5;
  int max_cameras = 64;    // the most max_error_mm may ask for
  int grid_points = 3000;  // the coarse lattice the search scores on (about)
};

struct RigPlan {
  CameraRig rig;       // named "ceiling-N" / "wall-N", with the volume
  int candidates = 0;  // poses considered
  int swaps = 0;       // improvements after the greedy pass
};

// Progress: a line of text now and then (may be empty).
using PlanProgress = std::function<void(const std::string&)>;

// The plan, or the reason there is none, naming the setting: a camera model without a usable
// image, a volume that is empty or under the floor, a ceiling below the volume, no candidate
// that sees the volume, a camera count or error target that cannot be met.
[[nodiscard]] std::expected<RigPlan, std::string> plan_rig(const Camera& model, const TrackingVolume& volume, const PlanSettings& settings,
                                                           const PlanProgress& progress = {});

}  // namespace rhot
