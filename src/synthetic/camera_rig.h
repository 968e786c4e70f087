#pragma once
// Camera rigs of the synthetic data sets, in COLMAP's convention: X_cam = R X_world + t, camera
// x right, y down, z forward; pinhole K with pixel (col, row) centred at (col + 0.5, row + 0.5).

#include <Eigen/Core>
#include <string>
#include <vector>

namespace hairmvs {

struct SyntheticView {
  std::string name;  // image file name, e.g. "g0_c.png"
  int width = 0;
  int height = 0;
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  // How the view was placed (for meta.json): azimuth 0 looks at the back of the head from +Y,
  // positive azimuth moves the camera towards -X; elevation above the target's horizon.
  double az_deg = 0;
  double el_deg = 0;
  double dist_m = 0;
  double roll_deg = 0;

  Eigen::Vector3d Centre() const { return -R.transpose() * t; }
  Eigen::Vector3d ToCamera(const Eigen::Vector3d& x_world) const { return R * x_world + t; }
  // Image point (SfM convention) of a camera-frame point with z > 0.
  Eigen::Vector2d Project(const Eigen::Vector3d& x_cam) const {
    return Eigen::Vector2d(K(0, 0) * x_cam.x() / x_cam.z() + K(0, 2),
                           K(1, 1) * x_cam.y() / x_cam.z() + K(1, 2));
  }
};

// Intrinsics of the shared sets scaled to `width`: focal 0.79977 width, principal point at the
// image centre, height round(2/3 width).
Eigen::Matrix3d SyntheticCalibration(int width, int* height);

// A camera at `centre` looking at `target`, world +Z up in the image (camera x = view x up),
// rotated by `roll_rad` about its axis.
SyntheticView LookAtView(const std::string& name, const Eigen::Vector3d& centre,
                         const Eigen::Vector3d& target, double roll_rad, const Eigen::Matrix3d& K,
                         int width, int height);
// The camera at azimuth/elevation/distance around `target` (see SyntheticView).
Eigen::Vector3d OrbitPosition(const Eigen::Vector3d& target, double az_deg, double el_deg,
                              double dist_m);

// The paper's T groups: centre, left and right 10 degrees apart in azimuth, bottom 10 degrees
// lower, 0.6 m from `target`; groups placed as in synth_straight_gantry (num_groups 1..8).
std::vector<SyntheticView> MakeGantryRig(int num_groups, const Eigen::Vector3d& target,
                                         int width);
// Handheld-like views around the head: azimuths spread over the circle with jitter, distance
// 0.45-0.8 m, elevation -10..45 degrees, roll within +-6 degrees, aim jittered by 2 cm.
std::vector<SyntheticView> MakeHandheldRig(int num_views, const Eigen::Vector3d& target,
                                           int width, uint64_t seed);

}  // namespace hairmvs
