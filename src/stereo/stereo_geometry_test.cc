#include "src/stereo/stereo_geometry.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "src/stereo/stereo_test_util.h"

namespace hairmvs {
namespace {

using testing_util::LookAtCamera;

TEST(StereoGeometry, ViewProjectionMatchesTheWorldPathAtEveryLevel) {
  const StereoCamera ref = LookAtCamera({0, 0, 0}, {0, 0, 1}, 100, 96, 72);
  const StereoCamera src = LookAtCamera({0.3, 0.1, 0.05}, {0, 0, 1}, 110, 90, 70, 0.4);
  for (int level = 0; level < 3; ++level) {
    const int rw = (96 + (1 << level) - 1) >> level, rh = (72 + (1 << level) - 1) >> level;
    const int sw = (90 + (1 << level) - 1) >> level, sh = (70 + (1 << level) - 1) >> level;
    const ViewProjection proj = ComputeViewProjection(ref, rw, rh, src, sw, sh);
    const StereoCamera r = ref.Scaled(rw, rh), s = src.Scaled(sw, sh);
    for (double depth : {0.7, 1.0, 1.6}) {
      const Eigen::Vector3d x(12.5, 30.5, 1.0);
      const Eigen::Vector3d world = r.R.transpose() * (depth * r.K.inverse() * x - r.t);
      const Eigen::Vector3d expected = s.K * (s.R * world + s.t);
      const Eigen::Vector3d got = depth * proj.H * x + proj.b;
      EXPECT_NEAR((got.hnormalized() - expected.hnormalized()).norm(), 0.0, 1e-9);
    }
  }
}

TEST(StereoGeometry, RollCorrectionCancelsARollAboutTheOpticalAxis) {
  // A strand seen at angle theta in the reference appears at theta + roll-induced rotation in
  // the source; exp(i psi) must undo that rotation of 2 theta.
  const StereoCamera ref = LookAtCamera({0, 0, 0}, {0, 0, 1}, 100, 96, 72);
  for (double roll : {0.0, 0.5, 1.0, -1.2}) {
    const StereoCamera src = LookAtCamera({0.2, 0, 0}, {0, 0, 1}, 100, 96, 72, roll);
    const ViewProjection proj = ComputeViewProjection(ref, 96, 72, src, 96, 72);
    // A short 3D segment on the plane z = 1 projected into both views.
    const Eigen::Vector3d a(0.0, 0.0, 1.0), b(0.02, 0.01, 1.0);
    auto angle = [](const StereoCamera& c, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
      const Eigen::Vector2d u = (c.K * (c.R * p + c.t)).hnormalized();
      const Eigen::Vector2d v = (c.K * (c.R * q + c.t)).hnormalized();
      return std::atan2(v.y() - u.y(), v.x() - u.x());
    };
    const double theta_ref = angle(ref, a, b), theta_src = angle(src, a, b);
    // Re(exp(-2i theta_ref) exp(2i theta_src) exp(i psi)) ~ 1 when corrected.
    const double corrected = std::cos(2 * (theta_src - theta_ref) + proj.psi_rad);
    EXPECT_GT(corrected, 0.98) << "roll " << roll;
  }
}

TEST(StereoGeometry, DepthLabelsSpanTheRangeInDepthOrInverseDepth) {
  for (bool inverse : {false, true}) {
    const DepthLabels labels(0.5, 2.0, 64, inverse);
    EXPECT_NEAR(labels.Depth(0), 0.5, 1e-12);
    EXPECT_NEAR(labels.Depth(63), 2.0, 1e-12);
    EXPECT_NEAR(labels.Label(labels.Depth(17.25)), 17.25, 1e-9);
  }
  const DepthLabels inverse(0.5, 2.0, 3, true);
  EXPECT_NEAR(1.0 / inverse.Depth(1), 0.5 * (1 / 0.5 + 1 / 2.0), 1e-12);
  const DepthLabels linear(0.5, 2.0, 3, false);
  EXPECT_NEAR(linear.Depth(1), 1.25, 1e-12);
}

}  // namespace
}  // namespace hairmvs
