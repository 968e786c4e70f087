#include "src/synthetic/camera_rig.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

#include "src/core/logging.h"
#include "src/synthetic/hair_model.h"

namespace hairmvs {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
// synth_straight_gantry: 767.783 px at 960 px wide.
constexpr double kFocalPerWidth = 767.783 / 960.0;
constexpr double kGantryDistanceM = 0.6;

struct GroupPlacement {
  double az_deg;
  double el_deg;  // of the centre camera; the bottom one is 10 degrees lower
};
// The groups of synth_straight_gantry/gt/meta.json, in its order.
constexpr GroupPlacement kGantryGroups[] = {{0, 5},    {-60, 5}, {60, 5},   {0, 35},
                                            {-120, 5}, {120, 5}, {-90, 35}, {90, 35}};

}  // namespace

Eigen::Matrix3d SyntheticCalibration(int width, int* height) {
  CHECK_GT(width, 0);
  *height = static_cast<int>(std::lround(width * 2.0 / 3.0));
  const double f = kFocalPerWidth * width;
  Eigen::Matrix3d K;
  K << f, 0, 0.5 * width, 0, f, 0.5 * *height, 0, 0, 1;
  return K;
}

Eigen::Vector3d OrbitPosition(const Eigen::Vector3d& target, double az_deg, double el_deg,
                              double dist_m) {
  const double az = az_deg * kDegToRad, el = el_deg * kDegToRad;
  return target + dist_m * Eigen::Vector3d(-std::cos(el) * std::sin(az),
                                           std::cos(el) * std::cos(az), std::sin(el));
}

SyntheticView LookAtView(const std::string& name, const Eigen::Vector3d& centre,
                         const Eigen::Vector3d& target, double roll_rad, const Eigen::Matrix3d& K,
                         int width, int height) {
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d x0 = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y0 = z.cross(x0);
  // Roll about the viewing axis.
  const Eigen::Vector3d x = std::cos(roll_rad) * x0 + std::sin(roll_rad) * y0;
  const Eigen::Vector3d y = z.cross(x);
  SyntheticView view;
  view.name = name;
  view.width = width;
  view.height = height;
  view.K = K;
  view.R.row(0) = x.transpose();
  view.R.row(1) = y.transpose();
  view.R.row(2) = z.transpose();
  view.t = -view.R * centre;
  view.dist_m = (target - centre).norm();
  view.roll_deg = roll_rad / kDegToRad;
  return view;
}

std::vector<SyntheticView> MakeGantryRig(int num_groups, const Eigen::Vector3d& target,
                                         int width) {
  CHECK_GE(num_groups, 1);
  CHECK_LE(num_groups, 8);
  int height = 0;
  const Eigen::Matrix3d K = SyntheticCalibration(width, &height);
  std::vector<SyntheticView> views;
  for (int g = 0; g < num_groups; ++g) {
    const GroupPlacement& p = kGantryGroups[g];
    // Centre, left, right, bottom (the paper's T).
    const struct {
      char tag;
      double daz, del;
    } members[] = {{'c', 0, 0}, {'l', -10, 0}, {'r', 10, 0}, {'b', 0, -10}};
    for (const auto& m : members) {
      char name[32];
      std::snprintf(name, sizeof(name), "g%d_%c.png", g, m.tag);
      const double az = p.az_deg + m.daz, el = p.el_deg + m.del;
      SyntheticView v = LookAtView(name, OrbitPosition(target, az, el, kGantryDistanceM), target,
                                   0.0, K, width, height);
      v.az_deg = az;
      v.el_deg = el;
      views.push_back(v);
    }
  }
  return views;
}

std::vector<SyntheticView> MakeHandheldRig(int num_views, const Eigen::Vector3d& target,
                                           int width, uint64_t seed) {
  CHECK_GE(num_views, 2);
  int height = 0;
  const Eigen::Matrix3d K = SyntheticCalibration(width, &height);
  SplitMix64 rng(DeriveSeed(seed, 2, 0));
  std::vector<SyntheticView> views;
  for (int i = 0; i < num_views; ++i) {
    const double az = -180.0 + 360.0 * (i + rng.Uniform(0.2, 0.8)) / num_views;
    const double el = rng.Uniform(-10.0, 45.0);
    const double dist = rng.Uniform(0.45, 0.8);
    const double roll = rng.Uniform(-6.0, 6.0);
    const Eigen::Vector3d aim =
        target + Eigen::Vector3d(rng.Uniform(-0.02, 0.02), rng.Uniform(-0.02, 0.02),
                                 rng.Uniform(-0.02, 0.02));
    char name[32];
    std::snprintf(name, sizeof(name), "h%02d.png", i);
    SyntheticView v =
        LookAtView(name, OrbitPosition(target, az, el, dist), aim, roll * kDegToRad, K, width,
                   height);
    v.az_deg = az;
    v.el_deg = el;
    v.dist_m = dist;
    views.push_back(v);
  }
  return views;
}

}  // namespace hairmvs
