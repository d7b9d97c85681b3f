#include "tracking/calib/HeadsetRegistration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <Eigen/Dense>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "tracking/media/Media.h"

namespace rhot {

namespace {

constexpr double kDegPerRadian = 180.0 / std::numbers::pi;
// Rotation errors are weighed as the displacement they make at this distance: 1 mrad as 0.1 mm.
constexpr double kRotationLever_m = 0.1;

Eigen::Vector3d rotation_vector(const Eigen::Quaterniond& q) {
  const Eigen::AngleAxisd aa(q.normalized());
  return aa.angle() * aa.axis();
}

// world_from_star = X * B * Y, residual of one sample: position (m) and orientation (scaled to m).
struct SampleError {
  Rigid3d a;  // world_from_star
  Rigid3d b;  // stage_from_head
  template <typename T>
  bool operator()(const T* x, const T* y, T* residual) const {
    // x, y: angle-axis (3) then translation (3).
    T p[3] = {T(y[3]), T(y[4]), T(y[5])};
    T q[3];
    const T bq[4] = {T(b.rotation.w()), T(b.rotation.x()), T(b.rotation.y()), T(b.rotation.z())};
    ceres::QuaternionRotatePoint(bq, p, q);
    for (int k = 0; k < 3; ++k) q[k] += T(b.translation[k]);
    T w[3];
    ceres::AngleAxisRotatePoint(x, q, w);
    for (int k = 0; k < 3; ++k) residual[k] = w[k] + x[3 + k] - T(a.translation[k]);
    // Orientation: a^-1 * x * b * y as a rotation vector.
    T xq[4], yq[4], xb[4], xby[4], err[4];
    ceres::AngleAxisToQuaternion(x, xq);
    ceres::AngleAxisToQuaternion(y, yq);
    ceres::QuaternionProduct(xq, bq, xb);
    ceres::QuaternionProduct(xb, yq, xby);
    const T ainv[4] = {T(a.rotation.w()), T(-a.rotation.x()), T(-a.rotation.y()), T(-a.rotation.z())};
    ceres::QuaternionProduct(ainv, xby, err);
    if (err[0] < T(0)) {
      for (T& e : err) e = -e;
    }
    // Small angles: the vector part is half the rotation vector.
    for (int k = 0; k < 3; ++k) residual[3 + k] = T(2.0 * kRotationLever_m) * err[1 + k];
    return true;
  }
};

std::array<double, 6> to_params(const Rigid3d& r) {
  const Eigen::Vector3d v = rotation_vector(r.rotation);
  return {v.x(), v.y(), v.z(), r.translation.x(), r.translation.y(), r.translation.z()};
}

Rigid3d from_params(const std::array<double, 6>& p) {
  const Eigen::Vector3d v(p[0], p[1], p[2]);
  const double angle = v.norm();
  Rigid3d r;
  r.rotation = angle > 0.0 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, v / angle)) : Eigen::Quaterniond::Identity();
  r.translation = Eigen::Vector3d(p[3], p[4], p[5]);
  return r;
}

// Relative motions between samples spread over the run (up to ~2,000 pairs).
std::vector<std::pair<std::size_t, std::size_t>> sample_pairs(std::size_t n) {
  const std::size_t stride = std::max<std::size_t>(1, n / 60);
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < n; i += stride) {
    for (std::size_t j = i + stride; j < n; j += stride) pairs.emplace_back(i, j);
  }
  return pairs;
}

struct ClosedForm {
  Rigid3d x;
  Rigid3d y;
  double turn_deg = 0.0;
  double second_axis_ratio = 0.0;
};

// AX = XB on the relative motions for X's rotation (its rotation vectors aligned, Kabsch) and
// translation (least squares), then Y from every sample, averaged.
std::expected<ClosedForm, std::string> closed_form(std::span<const HeadsetPoseSample> s, const HeadsetRegistrationSettings& settings) {
  const auto pairs = sample_pairs(s.size());
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
  ClosedForm out;
  std::vector<std::pair<Rigid3d, Rigid3d>> relative;
  for (const auto& [i, j] : pairs) {
    const Rigid3d a = s[i].world_from_star * s[j].world_from_star.inverse();
    const Rigid3d b = s[i].stage_from_head * s[j].stage_from_head.inverse();
    const Eigen::Vector3d alpha = rotation_vector(a.rotation);
    const Eigen::Vector3d beta = rotation_vector(b.rotation);
    out.turn_deg = std::max(out.turn_deg, beta.norm() * kDegPerRadian);
    h += alpha * beta.transpose();
    spread += beta * beta.transpose();
    relative.emplace_back(a, b);
  }
  if (out.turn_deg < settings.min_turn_deg) {
    char text[160];
    std::snprintf(text, sizeof(text), "the head turned at most %.2f degrees between samples; turn it by at least %.1f degrees",
                  out.turn_deg, settings.min_turn_deg);
    return std::unexpected(std::string(text));
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> axes(spread);
  out.second_axis_ratio = axes.eigenvalues()(1) / std::max(axes.eigenvalues()(2), 1e-30);
  if (out.second_axis_ratio < settings.min_second_axis_ratio) {
    return std::unexpected(std::string(
        "the head turned about one axis only: its offset along that axis cannot be told from the registration; nod and tilt it too"));
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d rx = svd.matrixU() * d * svd.matrixV().transpose();
  // (I - Ra) tx = ta - Rx tb for every relative motion.
  Eigen::MatrixXd m(3 * relative.size(), 3);
  Eigen::VectorXd rhs(3 * relative.size());
  for (std::size_t k = 0; k < relative.size(); ++k) {
    const auto& [a, b] = relative[k];
    m.block<3, 3>(static_cast<Eigen::Index>(3 * k), 0) = Eigen::Matrix3d::Identity() - a.rotation.toRotationMatrix();
    rhs.segment<3>(static_cast<Eigen::Index>(3 * k)) = a.translation - rx * b.translation;
  }
  out.x.rotation = Eigen::Quaterniond(rx).normalized();
  out.x.translation = m.colPivHouseholderQr().solve(rhs);
  // Y = B^-1 X^-1 A per sample: quaternions summed on one hemisphere, translations averaged.
  Eigen::Vector4d q_sum = Eigen::Vector4d::Zero();
  Eigen::Vector3d t_sum = Eigen::Vector3d::Zero();
  Eigen::Quaterniond first = Eigen::Quaterniond::Identity();  // the first sample's, set below
  for (std::size_t i = 0; i < s.size(); ++i) {
    const Rigid3d y = s[i].stage_from_head.inverse() * out.x.inverse() * s[i].world_from_star;
    if (i == 0) first = y.rotation;
    const double sign = first.dot(y.rotation) < 0.0 ? -1.0 : 1.0;
    q_sum += sign * y.rotation.coeffs();
    t_sum += y.translation;
  }
  out.y.rotation = Eigen::Quaterniond(q_sum.normalized());
  out.y.translation = t_sum / static_cast<double>(s.size());
  return out;
}

}  // namespace

std::expected<HeadsetRegistration, std::string> register_headset(std::span<const HeadsetPoseSample> samples,
                                                                 const HeadsetRegistrationSettings& settings) {
  if (samples.size() < settings.min_samples) {
    return std::unexpected("only " + std::to_string(samples.size()) + " samples of the headset's star and head; at least " +
                           std::to_string(settings.min_samples) + " are needed");
  }
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!samples[i].world_from_star.is_finite() || !samples[i].stage_from_head.is_finite() || !std::isfinite(samples[i].t_s)) {
      return std::unexpected("sample " + std::to_string(i) + " is not finite");
    }
  }
  auto initial = closed_form(samples, settings);
  if (!initial) return std::unexpected(initial.error());
  std::array<double, 6> x = to_params(initial->x);
  std::array<double, 6> y = to_params(initial->y);
  ceres::Problem problem;
  for (const HeadsetPoseSample& s : samples) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SampleError, 6, 6, 6>(new SampleError{s.world_from_star, s.stage_from_head}),
                             new ceres::HuberLoss(0.005), x.data(), y.data());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 100;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable()) return std::unexpected("the registration's refinement failed: " + summary.BriefReport());

  HeadsetRegistration r;
  r.world_from_stage = from_params(x);
  r.head_from_star = from_params(y);
  r.samples = samples.size();
  r.turn_deg = initial->turn_deg;
  r.second_axis_ratio = initial->second_axis_ratio;
  double sum_mm = 0.0, sum_deg = 0.0;
  for (const HeadsetPoseSample& s : samples) {
    const Rigid3d predicted = r.world_from_stage * s.stage_from_head * r.head_from_star;
    const double mm = 1e3 * (predicted.translation - s.world_from_star.translation).norm();
    const double deg = kDegPerRadian * s.world_from_star.rotation.angularDistance(predicted.rotation);
    r.residual_mm.push_back(mm);
    r.residual_deg.push_back(deg);
    sum_mm += mm * mm;
    sum_deg += deg * deg;
  }
  r.rms_mm = std::sqrt(sum_mm / static_cast<double>(samples.size()));
  r.rms_deg = std::sqrt(sum_deg / static_cast<double>(samples.size()));
  return r;
}

namespace {

cv::Mat to_cv(const Rigid3d& r) {
  cv::Mat m(4, 4, CV_64F);
  const Eigen::Matrix4d e = r.matrix();
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) m.at<double>(i, j) = e(i, j);
  }
  return m;
}

std::expected<Rigid3d, std::string> rigid_from(const cv::FileNode& node, const std::string& where) {
  if (node.empty()) return std::unexpected(where + ": missing");
  cv::Mat m;
  try {
    node >> m;
  } catch (const cv::Exception&) {
    return std::unexpected(where + ": not a matrix");
  }
  if (m.rows != 4 || m.cols != 4) return std::unexpected(where + ": expected a 4 x 4 matrix");
  m.convertTo(m, CV_64F);
  Eigen::Matrix4d e;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) e(i, j) = m.at<double>(i, j);
  }
  if (!e.allFinite()) return std::unexpected(where + ": a value is not finite");
  const Eigen::Matrix3d rot = e.topLeftCorner<3, 3>();
  if ((rot.transpose() * rot - Eigen::Matrix3d::Identity()).norm() > 1e-6 || rot.determinant() < 0.0 ||
      (e.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9) {
    return std::unexpected(where + ": not a rigid transform (its rotation is not orthonormal, or its last row is not 0 0 0 1)");
  }
  Rigid3d r;
  r.rotation = Eigen::Quaterniond(rot).normalized();
  r.translation = e.topRightCorner<3, 1>();
  return r;
}

}  // namespace

std::expected<void, std::string> write_headset_registration(const std::filesystem::path& file, const HeadsetRegistration& r) {
  try {
    cv::FileStorage fs(file.string(), cv::FileStorage::WRITE);
    if (!fs.isOpened()) return std::unexpected("cannot write " + file.string());
    fs.writeComment("rhot: the camera rig registered to the headset's STAGE space (rhot-calib headset; docs/openxr.md)");
    fs << "world_from_stage" << to_cv(r.world_from_stage);
    fs << "head_from_star" << to_cv(r.head_from_star);
    fs << "samples" << static_cast<int>(r.samples);
    fs << "rms_mm" << r.rms_mm;
    fs << "rms_deg" << r.rms_deg;
    fs << "turn_deg" << r.turn_deg;
  } catch (const cv::Exception& e) {
    return std::unexpected("cannot write " + file.string() + ": " + e.what());
  }
  return {};
}

std::expected<HeadsetRegistration, std::string> read_headset_registration(const std::filesystem::path& file) {
  const std::string name = file.string();
  cv::FileStorage fs;
  try {
    if (!fs.open(name, cv::FileStorage::READ)) return std::unexpected(name + ": cannot be read as OpenCV YAML");
  } catch (const cv::Exception&) {
    return std::unexpected(name + ": not OpenCV YAML");
  }
  HeadsetRegistration r;
  auto stage = rigid_from(fs["world_from_stage"], name + ": world_from_stage");
  if (!stage) return std::unexpected(stage.error());
  auto star = rigid_from(fs["head_from_star"], name + ": head_from_star");
  if (!star) return std::unexpected(star.error());
  r.world_from_stage = *stage;
  r.head_from_star = *star;
  if (!fs["samples"].empty() && fs["samples"].isInt()) r.samples = static_cast<std::size_t>(std::max(0, static_cast<int>(fs["samples"])));
  if (!fs["rms_mm"].empty() && fs["rms_mm"].isReal()) r.rms_mm = static_cast<double>(fs["rms_mm"]);
  if (!fs["rms_deg"].empty() && fs["rms_deg"].isReal()) r.rms_deg = static_cast<double>(fs["rms_deg"]);
  return r;
}

std::expected<void, std::string> write_registration_picture(const std::filesystem::path& file, std::span<const HeadsetPoseSample> samples,
                                                            const HeadsetRegistration& r) {
  constexpr int kWidth = 960, kPlot = 200, kMargin = 50;
  cv::Mat image(2 * kPlot + 3 * kMargin, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const double t0 = samples.empty() ? 0.0 : samples.front().t_s;
  const double t1 = samples.empty() ? 1.0 : std::max(samples.back().t_s, t0 + 1e-3);
  const auto plot = [&](const std::vector<double>& values, double rms, int top, const std::string& unit, const cv::Scalar& colour) {
    const double top_value = std::max(3.0 * rms, 1e-6);  // samples beyond three times the RMS sit on the top edge
    cv::rectangle(image, {kMargin, top}, {kWidth - kMargin, top + kPlot}, cv::Scalar(200, 200, 200));
    const int rms_y = top + kPlot - static_cast<int>(kPlot * std::min(1.0, rms / top_value));
    cv::line(image, {kMargin, rms_y}, {kWidth - kMargin, rms_y}, cv::Scalar(120, 120, 120), 1, cv::LINE_AA);
    for (std::size_t i = 0; i < values.size() && i < samples.size(); ++i) {
      const int x = kMargin + static_cast<int>((kWidth - 2 * kMargin) * (samples[i].t_s - t0) / (t1 - t0));
      const int y = top + kPlot - static_cast<int>(kPlot * std::min(1.0, values[i] / top_value));
      cv::circle(image, {x, y}, 2, colour, cv::FILLED, cv::LINE_AA);
    }
    char text[160];
    std::snprintf(text, sizeof(text), "%s error per sample (RMS %.3f, grey line; top %.3f)", unit.c_str(), rms, top_value);
    cv::putText(image, text, {kMargin, top - 8}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  };
  plot(r.residual_mm, r.rms_mm, kMargin, "position (mm)", cv::Scalar(200, 90, 30));
  plot(r.residual_deg, r.rms_deg, 2 * kMargin + kPlot, "orientation (degrees)", cv::Scalar(40, 40, 200));
  char caption[200];
  std::snprintf(caption, sizeof(caption), "headset registration: %zu samples over %.1f s, the head turned up to %.1f degrees", r.samples,
                t1 - t0, r.turn_deg);
  cv::putText(image, caption, {kMargin, image.rows - 15}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return write_image(file, image);
}

}  // namespace rhot
