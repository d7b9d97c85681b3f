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

#include <cstddef>
#include <expected>
#include <filesystem>
#include <string>

#include "tracking/camera/Camera.h"

namespace rhot {

// The most cameras a rig may have. rhot-plan places at most this many (the largest rig rhot makes;
// the largest shipped, assets/rigs/seed-wiimote-54.yaml, has 54), and tracking costs a few
// milliseconds per camera and frame: a rig of 10,000 cameras took 48 s a frame. check_rig, and so
// load_rig and save_rig, refuse more, naming the cap.
inline constexpr std::size_t kMaxRigCameras = 256;

[[nodiscard]] std::expected<CameraRig, std::string> load_rig(const std::filesystem::path& file);
[[nodiscard]] std::expected<void, std::string> save_rig(const CameraRig& rig, const std::filesystem::path& file);

// A rig file read for its cameras' intrinsics only (names, image sizes, camera matrices,
// distortion), as calibration reads the output of `rhot-calib intrinsics`: poses are not read (they
// may be missing, identity for every camera, or anything else), and every camera comes back at
// the world origin (cam_from_world the identity). Everything else is read and checked as load_rig
// does (check_rig_intrinsics).
[[nodiscard]] std::expected<CameraRig, std::string> load_rig_intrinsics(const std::filesystem::path& file);

// Consistency of a rig from any source: at least one camera and at most kMaxRigCameras, unique
// non-empty names, positive image sizes and focal lengths, principal points inside the image,
// finite values, proper rotations, distinct camera centres, a tracking volume of positive finite
// size. The message names the camera and the field.
[[nodiscard]] std::expected<void, std::string> check_rig(const CameraRig& rig);
// The same without the poses (finite, distinct centres): for cameras known by their intrinsics only.
[[nodiscard]] std::expected<void, std::string> check_rig_intrinsics(const CameraRig& rig);

}  // namespace rhot
