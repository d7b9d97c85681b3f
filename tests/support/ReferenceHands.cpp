#include "tests/support/ReferenceHands.h"

#include "engine/math/EigenGlm.h"
#include "tracking/hand/HandJoints.h"

namespace rhot {

std::array<HandDrawInput, 2> reference_hands() {
  std::array<HandDrawInput, 2> hands;
  const std::array<HandSide, 2> sides{HandSide::kLeft, HandSide::kRight};
  for (std::size_t h = 0; h < 2; ++h) {
    const HandPose pose = reference_open_hand(sides[h]);
    // Wrists 15 cm either side of centre, 20 cm above the table top (0.74 m), 25 cm in front.
    const glm::vec3 wrist(h == 0 ? -0.15f : 0.15f, 0.94f, -0.25f);
    for (std::size_t j = 0; j < 26; ++j) {
      hands[h].joint_world[j] = wrist + to_glm(pose.position_m[j]);
      hands[h].radius_m[j] = static_cast<float>(pose.radius_m[j]);
    }
  }
  return hands;
}

}  // namespace rhot
