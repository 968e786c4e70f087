#include "src/stereo/stereo_geometry.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "src/core/logging.h"

namespace hairmvs {

std::array<float, 16> ViewProjection::Packed(float weight) const {
  std::array<float, 16> packed{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) packed[3 * r + c] = static_cast<float>(H(r, c));
    packed[9 + r] = static_cast<float>(b(r));
  }
  packed[12] = static_cast<float>(std::cos(psi_rad));
  packed[13] = static_cast<float>(std::sin(psi_rad));
  packed[14] = plane_homography ? 1.0f : 0.0f;
  packed[15] = weight;
  return packed;
}

Eigen::Vector3d Epipole(const StereoCamera& camera, const Eigen::Vector3d& other_center) {
  return camera.K * (camera.R * other_center + camera.t);
}

bool EpipoleInImage(const StereoCamera& camera, const Eigen::Vector3d& other_center) {
  const Eigen::Vector3d e = Epipole(camera, other_center);
  if (e.z() == 0) return false;
  const Eigen::Vector2d x = e.hnormalized();
  return x.x() >= 0 && x.x() <= camera.width && x.y() >= 0 && x.y() <= camera.height;
}

double EpipoleAngle(const StereoCamera& camera, const Eigen::Vector3d& other_center) {
  const Eigen::Vector3d e = Epipole(camera, other_center);
  // (e.x / e.z - cx, e.y / e.z - cy) scaled by e.z: the sign of e.z flips the vector, which
  // changes the angle by pi; the correction uses 2 phi, so that does not matter.
  const double vx = e.x() - camera.K(0, 2) * e.z();
  const double vy = e.y() - camera.K(1, 2) * e.z();
  return std::atan2(vy, vx);
}

double ViewingAngleDeg(const StereoCamera& a, const StereoCamera& b) {
  // The third rows of R: the optical axes in the world frame.
  const double c = std::clamp(a.R.row(2).dot(b.R.row(2)), -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

double ImageScaleRatio(const StereoCamera& ref, const StereoCamera& src, double depth) {
  const Eigen::Vector3d point = ref.R.transpose() * (Eigen::Vector3d(0, 0, depth) - ref.t);
  const double z_src = src.R.row(2).dot(point) + src.t.z();
  if (!(z_src > 0) || !(depth > 0)) return 0.0;
  return (MeanFocalPx(src.K) / z_src) / (MeanFocalPx(ref.K) / depth);
}

double LabelStepPxPerRadian(const StereoCamera& ref, const DepthLabels& labels) {
  const double v = labels.MiddleLabel();
  const double near = labels.Depth(v), far = labels.Depth(v + 1);
  return MeanFocalPx(ref.K) * std::abs(1.0 / near - 1.0 / far) * 0.5 * (near + far);
}

ViewProjection ComputeViewProjection(const StereoCamera& ref, const StereoCamera& src,
                                     OrientationTransfer transfer) {
  // X_src = R_rel X_ref + t_rel, X_ref = D K_r^-1 x.
  const Eigen::Matrix3d R_rel = src.R * ref.R.transpose();
  const Eigen::Vector3d t_rel = src.t - R_rel * ref.t;
  ViewProjection projection;
  projection.H = src.K * R_rel * ref.K.inverse();
  projection.b = src.K * t_rel;
  projection.plane_homography = transfer == OrientationTransfer::kPlaneHomography;
  if (transfer == OrientationTransfer::kEpipoleRoll) {
    projection.psi_rad =
        2.0 * (EpipoleAngle(ref, src.Center()) - EpipoleAngle(src, ref.Center()));
  }
  return projection;
}

double LevelPixelsPerPixel(int level, int grid_level) {
  return std::ldexp(1.0, grid_level - level);
}

Eigen::Vector2d TransferDirection(const ViewProjection& projection, double depth, double x,
                                  double y, const Eigen::Vector2d& direction,
                                  const Eigen::Vector2d& log_depth_gradient) {
  // u(x, y) = D H (x, y, 1) + b; the image point is (u.x / u.z, u.y / u.z). Moving along the
  // strand changes u by (a positive multiple of) h = H ((t, 0) + (g . t) (x, y, 1)), and the
  // image point by (h.x - p_x h.z, h.y - p_y h.z) / u.z, u.z > 0 in front of the source.
  const Eigen::Matrix3d& H = projection.H;
  const Eigen::Vector3d x_h(x, y, 1.0);
  const Eigen::Vector3d u = depth * H * x_h + projection.b;
  const double px = u.x() / u.z(), py = u.y() / u.z();
  const Eigen::Vector3d h =
      H * (Eigen::Vector3d(direction.x(), direction.y(), 0.0) +
           log_depth_gradient.dot(direction) * x_h);
  return {h.x() - px * h.z(), h.y() - py * h.z()};
}

int NearestLevel0Pixel(int index, int level, int size0) {
  const int scale = 1 << level;
  return std::min(size0 - 1, index * scale + scale / 2);
}

FloatMap LogDepthGradient(const FloatMap& depth0, int level, int width, int height,
                          double focal_x_px, double focal_y_px, double max_tilt_deg) {
  CHECK_EQ(depth0.Channels(), 1);
  FloatMap gradient(width, height, 2, 0.0f);
  const int scale = 1 << level;
  const int step = std::max(2, scale);
  const double max_tangent = std::tan(max_tilt_deg * M_PI / 180.0);
  auto log_depth = [&](int r, int c, double* value) {
    if (r < 0 || c < 0 || r >= depth0.Height() || c >= depth0.Width()) return false;
    const float d = depth0.At(r, c);
    if (!(d > 0)) return false;
    *value = std::log(static_cast<double>(d));
    return true;
  };
  for (int r = 0; r < height; ++r) {
    const int r0 = NearestLevel0Pixel(r, level, depth0.Height());
    for (int c = 0; c < width; ++c) {
      const int c0 = NearestLevel0Pixel(c, level, depth0.Width());
      double left, right, up, down;
      if (!log_depth(r0, c0 - step, &left) || !log_depth(r0, c0 + step, &right) ||
          !log_depth(r0 - step, c0, &up) || !log_depth(r0 + step, c0, &down)) {
        continue;
      }
      Eigen::Vector2d g((right - left) / (2 * step), (down - up) / (2 * step));
      const double tangent = Eigen::Vector2d(g.x() * focal_x_px, g.y() * focal_y_px).norm();
      if (tangent > max_tangent) g *= max_tangent / tangent;
      gradient.At(r, c, 0) = static_cast<float>(scale * g.x());
      gradient.At(r, c, 1) = static_cast<float>(scale * g.y());
    }
  }
  return gradient;
}

DepthLabels::DepthLabels(double depth_min_in, double depth_max_in, int num_labels_in,
                         bool inverse_in)
    : depth_min(depth_min_in), depth_max(depth_max_in), num_labels(num_labels_in),
      inverse(inverse_in) {
  CHECK_GT(depth_min, 0.0);
  CHECK_GT(depth_max, depth_min);
  CHECK_GE(num_labels, 2);
  const double t0 = inverse ? 1.0 / depth_min : depth_min;
  const double t1 = inverse ? 1.0 / depth_max : depth_max;
  a = t0;
  b = (t1 - t0) / (num_labels - 1);
}

}  // namespace hairmvs
