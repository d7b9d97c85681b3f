#pragma once
// Hands to draw in renderer tests and benchmarks, without tracking.

#include <array>

#include "engine/render/SceneRenderer.h"

namespace rhot {

// The reference open hands (tracking/hand) placed in front of a seated user, palms down above the
// default scene's table.
std::array<HandDrawInput, 2> reference_hands();

}  // namespace rhot
