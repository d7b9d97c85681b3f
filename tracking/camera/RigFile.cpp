#include "tracking/camera/RigFile.h"

#include <cmath>
#include <set>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace rhot {

namespace {

struct Failure {
  std::string message;
};

std::string camera_label(std::size_t i, const std::string& name) {
  return "cameras[" + std::to_string(i) + "]" + (name.empty() ? "" : " (\"" + name + "\")");
}

// Reads an rows x cols matrix of numbers from a node.
Eigen::MatrixXd read_matrix(const cv::FileNode& parent, const char* key, int rows, int cols, const std::string& where) {
  const std::string label = where.empty() ? std::string(key) : where + "." + key;
  const cv::FileNode node = parent[key];
  if (node.empty()) throw Failure{label + ": missing"};
  cv::Mat m;
  try {
    node >> m;
  } catch (const cv::Exception&) {
    m = cv::Mat();
  }
  if (m.empty() || m.channels() != 1) {
    throw Failure{label + ": expected an !!opencv-matrix of " + std::to_string(rows) + "x" + std::to_string(cols) + " numbers"};
  }
  if (m.rows * m.cols != rows * cols || (m.rows != rows && !(rows == 1 || cols == 1))) {
    throw Failure{label + ": expected " + std::to_string(rows) + "x" + std::to_string(cols) + ", got " + std::to_string(m.rows) + "x" +
                  std::to_string(m.cols)};
  }
  cv::Mat d;
  m.convertTo(d, CV_64F);
  Eigen::MatrixXd out(rows, cols);
  for (int i = 0; i < rows * cols; ++i) {
    const double v = d.at<double>(i / d.cols, i % d.cols);
    if (!std::isfinite(v)) throw Failure{label + ": contains a value that is not finite"};
    out(i / cols, i % cols) = v;
  }
  return out;
}

int read_int(const cv::FileNode& parent, const char* key, const std::string& where) {
  const cv::FileNode node = parent[key];
  if (node.empty()) throw Failure{where + "." + key + ": missing"};
  if (!node.isInt()) throw Failure{where + "." + key + ": expected an integer"};
  return static_cast<int>(node);
}

std::string too_many_cameras(std::size_t count) {
  return "cameras: a rig may have at most " + std::to_string(kMaxRigCameras) + " cameras, got " + std::to_string(count);
}

// Camera i of the file's sequence; its pose read where `poses` says, else left at the identity.
Camera read_camera(const cv::FileNode& node, std::size_t i, bool poses) {
  std::string where = camera_label(i, "");
  if (!node.isMap()) throw Failure{where + ": expected a map with name, image_width, image_height, camera_matrix, ..."};
  Camera c;
  const cv::FileNode n = node["name"];
  if (n.empty() || !n.isString()) throw Failure{where + ".name: missing or not a string"};
  c.name = static_cast<std::string>(n);
  where = camera_label(i, c.name);
  c.intrinsics.width_px = read_int(node, "image_width", where);
  c.intrinsics.height_px = read_int(node, "image_height", where);
  const Eigen::MatrixXd k = read_matrix(node, "camera_matrix", 3, 3, where);
  if (k(0, 1) != 0.0 || k(1, 0) != 0.0 || k(2, 0) != 0.0 || k(2, 1) != 0.0 || k(2, 2) != 1.0) {
    throw Failure{where + ".camera_matrix: expected [fx 0 cx; 0 fy cy; 0 0 1] (no skew)"};
  }
  c.intrinsics.fx = k(0, 0);
  c.intrinsics.fy = k(1, 1);
  c.intrinsics.cx = k(0, 2);
  c.intrinsics.cy = k(1, 2);
  const Eigen::MatrixXd d = read_matrix(node, "distortion_coefficients", 1, 5, where);
  for (int j = 0; j < 5; ++j) c.intrinsics.distortion[static_cast<std::size_t>(j)] = d(j);
  if (!poses) return c;
  const Eigen::Matrix3d r = read_matrix(node, "rotation", 3, 3, where);
  if ((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > 1e-6 || r.determinant() < 0.0) {
    throw Failure{where + ".rotation: not a rotation matrix (expected orthonormal with determinant +1)"};
  }
  c.cam_from_world.rotation = Eigen::Quaterniond(r).normalized();
  c.cam_from_world.translation = read_matrix(node, "translation", 3, 1, where);
  return c;
}

// check_rig, and check_rig_intrinsics where `poses` is false.
std::expected<void, std::string> check(const CameraRig& rig, bool poses) {
  if (rig.cameras.empty()) return std::unexpected(std::string("cameras: a rig needs at least one camera"));
  if (rig.cameras.size() > kMaxRigCameras) return std::unexpected(too_many_cameras(rig.cameras.size()));
  if (rig.volume) {
    if (!rig.volume->centre_m.allFinite()) return std::unexpected(std::string("volume_centre: contains a value that is not finite"));
    if (!rig.volume->size_m.allFinite() || !(rig.volume->size_m.minCoeff() > 0.0)) {
      return std::unexpected(std::string("volume_size: every side must be positive and finite"));
    }
  }
  std::set<std::string> names;
  for (std::size_t i = 0; i < rig.cameras.size(); ++i) {
    const Camera& c = rig.cameras[i];
    const std::string where = camera_label(i, c.name);
    const CameraIntrinsics& k = c.intrinsics;
    if (c.name.empty()) return std::unexpected(where + ".name: missing or empty");
    if (!names.insert(c.name).second) return std::unexpected(where + ".name: duplicate name \"" + c.name + "\"");
    if (k.width_px <= 0 || k.height_px <= 0 || k.width_px > 65536 || k.height_px > 65536) {
      return std::unexpected(where + ".image_width/image_height: expected 1 to 65536 pixels, got " + std::to_string(k.width_px) + "x" +
                             std::to_string(k.height_px));
    }
    for (const double v : {k.fx, k.fy, k.cx, k.cy}) {
      if (!std::isfinite(v)) return std::unexpected(where + ".camera_matrix: contains a value that is not finite");
    }
    for (const double v : k.distortion) {
      if (!std::isfinite(v)) return std::unexpected(where + ".distortion_coefficients: contains a value that is not finite");
    }
    if (!(k.fx > 0.0) || !(k.fy > 0.0)) return std::unexpected(where + ".camera_matrix: focal lengths fx and fy must be positive");
    if (k.cx < 0.0 || k.cx > k.width_px || k.cy < 0.0 || k.cy > k.height_px) {
      return std::unexpected(where + ".camera_matrix: the principal point (" + std::to_string(k.cx) + ", " + std::to_string(k.cy) +
                             ") lies outside the " + std::to_string(k.width_px) + "x" + std::to_string(k.height_px) + " image");
    }
    if (poses && !c.cam_from_world.is_finite()) {
      return std::unexpected(where + ".rotation/translation: contains a value that is not finite");
    }
  }
  if (!poses) return {};
  for (std::size_t i = 0; i < rig.cameras.size(); ++i) {
    for (std::size_t j = i + 1; j < rig.cameras.size(); ++j) {
      if ((rig.cameras[i].centre_world() - rig.cameras[j].centre_world()).norm() < 1e-6) {
        return std::unexpected(camera_label(j, rig.cameras[j].name) + ".translation: same position as " +
                               camera_label(i, rig.cameras[i].name));
      }
    }
  }
  return {};
}

// load_rig, and load_rig_intrinsics where `poses` is false.
std::expected<CameraRig, std::string> load(const std::filesystem::path& file, bool poses) {
  const std::string path = file.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) return std::unexpected(path + ": rig file not found");
  CameraRig rig;
  try {
    cv::FileStorage fs;
    try {
      if (!fs.open(path, cv::FileStorage::READ)) return std::unexpected(path + ": cannot open as OpenCV YAML");
    } catch (const cv::Exception& e) {
      return std::unexpected(path + ": not OpenCV FileStorage YAML: " + e.msg);
    }
    const cv::FileNode name = fs["rig_name"];
    if (!name.empty() && name.isString()) rig.name = static_cast<std::string>(name);
    const cv::FileNode cameras = fs["cameras"];
    if (cameras.empty()) throw Failure{"cameras: missing"};
    if (!cameras.isSeq()) throw Failure{"cameras: expected a sequence of cameras"};
    if (cameras.size() > kMaxRigCameras) throw Failure{too_many_cameras(cameras.size())};  // before reading them all
    for (std::size_t i = 0; i < cameras.size(); ++i) rig.cameras.push_back(read_camera(cameras[static_cast<int>(i)], i, poses));
    const bool has_centre = !fs["volume_centre"].empty();
    const bool has_size = !fs["volume_size"].empty();
    if (has_centre != has_size)
      throw Failure{has_centre ? "volume_size: missing (volume_centre needs it)" : "volume_centre: missing (volume_size needs it)"};
    if (has_centre) {
      const cv::FileNode root = fs.root();
      rig.volume = TrackingVolume{read_matrix(root, "volume_centre", 3, 1, ""), read_matrix(root, "volume_size", 3, 1, "")};
    }
  } catch (const Failure& f) {
    return std::unexpected(path + ": " + f.message);
  } catch (const cv::Exception& e) {
    return std::unexpected(path + ": " + e.msg);
  }
  if (auto ok = check(rig, poses); !ok) return std::unexpected(path + ": " + ok.error());
  return rig;
}

}  // namespace

std::expected<void, std::string> check_rig(const CameraRig& rig) { return check(rig, true); }

std::expected<void, std::string> check_rig_intrinsics(const CameraRig& rig) { return check(rig, false); }

std::expected<CameraRig, std::string> load_rig(const std::filesystem::path& file) { return load(file, true); }

std::expected<CameraRig, std::string> load_rig_intrinsics(const std::filesystem::path& file) { return load(file, false); }

std::expected<void, std::string> save_rig(const CameraRig& rig, const std::filesystem::path& file) {
  if (auto ok = check_rig(rig); !ok) return std::unexpected(file.string() + ": not saved: " + ok.error());
  try {
    cv::FileStorage fs(file.string(), cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
    if (!fs.isOpened()) return std::unexpected(file.string() + ": cannot write");
    fs << "rig_name" << rig.name;
    fs << "cameras"
       << "[";
    for (const Camera& c : rig.cameras) {
      const CameraIntrinsics& k = c.intrinsics;
      const cv::Matx33d camera_matrix(k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0);
      const cv::Matx<double, 1, 5> dist(k.distortion[0], k.distortion[1], k.distortion[2], k.distortion[3], k.distortion[4]);
      const Eigen::Matrix3d r = c.cam_from_world.rotation.toRotationMatrix();
      cv::Matx33d rotation;
      for (int i = 0; i < 9; ++i) rotation.val[i] = r(i / 3, i % 3);
      const Eigen::Vector3d t = c.cam_from_world.translation;
      fs << "{"
         << "name" << c.name << "image_width" << k.width_px << "image_height" << k.height_px << "camera_matrix" << cv::Mat(camera_matrix)
         << "distortion_coefficients" << cv::Mat(dist) << "rotation" << cv::Mat(rotation) << "translation"
         << cv::Mat(cv::Matx31d(t.x(), t.y(), t.z())) << "}";
    }
    fs << "]";
    if (rig.volume) {
      const Eigen::Vector3d& c = rig.volume->centre_m;
      const Eigen::Vector3d& z = rig.volume->size_m;
      fs << "volume_centre" << cv::Mat(cv::Matx31d(c.x(), c.y(), c.z()));
      fs << "volume_size" << cv::Mat(cv::Matx31d(z.x(), z.y(), z.z()));
    }
  } catch (const cv::Exception& e) {
    return std::unexpected(file.string() + ": cannot write: " + e.msg);
  }
  return {};
}

}  // namespace rhot
