#pragma once
// Camera rigs as OpenCV FileStorage YAML, readable by OpenCV tools (cv::FileStorage):
//
//   %YAML:1.0
//   ---
//   rig_name: "seated-4"
//   cameras:
//     - name: "front-left"
//       image_width: 1280
//       image_height: 720
//       camera_matrix: !!opencv-matrix       3x3, [fx 0 cx; 0 fy cy; 0 0 1]
//       distortion_coefficients: !!opencv-matrix   1x5, k1 k2 p1 p2 k3
//       rotation: !!opencv-matrix             3x3, cam_from_world
//       translation: !!opencv-matrix          3x1, cam_from_world, metres
//   volume_centre: !!opencv-matrix    optional, 3x1: the tracked box's centre in the world, metres
//   volume_size: !!opencv-matrix      optional (with volume_centre), 3x1: its size X Y Z, metres
//
// Every problem is reported as one message naming the file, the camera and the field.

#include <expected>
#include <filesystem>
#include <string>

#include "tracking/camera/Camera.h"

namespace rhot {

[[nodiscard]] std::expected<CameraRig, std::string> load_rig(const std::filesystem::path& file);
[[nodiscard]] std::expected<void, std::string> save_rig(const CameraRig& rig, const std::filesystem::path& file);

// Consistency of a rig from any source: at least one camera, unique non-empty names, positive
// image sizes and focal lengths, principal points inside the image, finite values, proper
// rotations, distinct camera centres, a tracking volume of positive finite size. The message names the camera and the field.
[[nodiscard]] std::expected<void, std::string> check_rig(const CameraRig& rig);

}  // namespace rhot
