#include "src/stereo/stereo_geometry.h"

#include <Eigen/Dense>
#include <cmath>

#include "src/core/logging.h"

namespace hairmvs {

StereoCamera StereoCamera::Scaled(int new_width, int new_height) const {
  StereoCamera scaled = *this;
  const double sx = static_cast<double>(new_width) / width;
  const double sy = static_cast<double>(new_height) / height;
  // Continuous image coordinates scale exactly in the SfM convention (the image spans [0, W]).
  scaled.K.row(0) *= sx;
  scaled.K.row(1) *= sy;
  scaled.width = new_width;
  scaled.height = new_height;
  return scaled;
}

StereoCamera StereoCamera::PyramidLevel(int level) const {
  CHECK_GE(level, 0);
  StereoCamera scaled = *this;
  for (int l = 0; l < level; ++l) {
    scaled.K.row(0) *= 0.5;
    scaled.K.row(1) *= 0.5;
    scaled.width = (scaled.width + 1) / 2;
    scaled.height = (scaled.height + 1) / 2;
  }
  return scaled;
}

std::array<float, 16> ViewProjection::Packed() const {
  std::array<float, 16> packed{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) packed[3 * r + c] = static_cast<float>(H(r, c));
    packed[9 + r] = static_cast<float>(b(r));
  }
  packed[12] = static_cast<float>(std::cos(psi_rad));
  packed[13] = static_cast<float>(std::sin(psi_rad));
  packed[14] = plane_homography ? 1.0f : 0.0f;
  return packed;
}

double EpipoleAngle(const StereoCamera& camera, const Eigen::Vector3d& other_center) {
  const Eigen::Vector3d e = camera.K * (camera.R * other_center + camera.t);
  // (e.x / e.z - cx, e.y / e.z - cy) scaled by e.z: the sign of e.z flips the vector, which
  // changes the angle by pi; the correction uses 2 phi, so that does not matter.
  const double vx = e.x() - camera.K(0, 2) * e.z();
  const double vy = e.y() - camera.K(1, 2) * e.z();
  return std::atan2(vy, vx);
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
                                  double y, const Eigen::Vector2d& direction) {
  // u(x, y) = D H (x, y, 1) + b; the image point is (u.x / u.z, u.y / u.z). Its Jacobian is
  // D / u.z times rows (H_0 - p_x H_2) and (H_1 - p_y H_2) (first two columns); D / u.z > 0
  // in front of the source.
  const Eigen::Matrix3d& H = projection.H;
  const Eigen::Vector3d u = depth * H * Eigen::Vector3d(x, y, 1.0) + projection.b;
  const double px = u.x() / u.z(), py = u.y() / u.z();
  return {(H(0, 0) - px * H(2, 0)) * direction.x() + (H(0, 1) - px * H(2, 1)) * direction.y(),
          (H(1, 0) - py * H(2, 0)) * direction.x() + (H(1, 1) - py * H(2, 1)) * direction.y()};
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
