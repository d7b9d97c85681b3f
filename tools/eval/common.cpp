// What rhot-eval's subcommands share: the evaluation box, percentiles.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "engine/sim/GraspScenarios.h"
#include "engine/scene/SceneLoader.h"
#include "tracking/camera/RigFile.h"
#include "tracking/geometry/Matching.h"
#include "tracking/sim/HandMotions.h"
#include "tracking/hand/HandTracker.h"
#include "tracking/rigid/StarTracker.h"
#include "tracking/sim/SimulatedRig.h"

#include "tools/eval/Eval.h"

namespace rhot::eval {

Eigen::Vector3d axes_meeting_point(const rhot::CameraRig& rig) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const rhot::Camera& c : rig.cameras) {
    const Eigen::Vector3d o = c.centre_world();
    const Eigen::Vector3d d = c.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitZ();
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += p;
    b += p * o;
  }
  return a.ldlt().solve(b);
}

Box evaluation_box(const rhot::CameraRig& rig, const std::vector<double>& size, const std::vector<double>& centre) {
  Box box{axes_meeting_point(rig), Eigen::Vector3d::Ones()};
  if (rig.volume) box = {rig.volume->centre_m, rig.volume->size_m};
  if (size.size() == 3) box.size = {size[0], size[1], size[2]};
  if (centre.size() == 3) box.centre = {centre[0], centre[1], centre[2]};
  return box;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::clamp<std::size_t>(rank, 1, v.size()) - 1];
}

}  // namespace rhot::eval
