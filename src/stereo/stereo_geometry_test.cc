#include "src/stereo/stereo_geometry.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "src/orientation/orientation_field.h"
#include "src/stereo/stereo_test_util.h"

namespace hairmvs {
namespace {

using testing_util::LookAtCamera;

TEST(StereoGeometry, ViewProjectionMatchesTheWorldPathAtEveryLevel) {
  const StereoCamera ref = LookAtCamera({0, 0, 0}, {0, 0, 1}, 100, 96, 72);
  const StereoCamera src = LookAtCamera({0.3, 0.1, 0.05}, {0, 0, 1}, 110, 90, 70, 0.4);
  for (int level = 0; level < 3; ++level) {
    const StereoCamera r = ref.PyramidLevel(level), s = src.PyramidLevel(level);
    const ViewProjection proj = ComputeViewProjection(r, s, OrientationTransfer::kEpipoleRoll);
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
    const ViewProjection proj =
        ComputeViewProjection(ref, src, OrientationTransfer::kEpipoleRoll);
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

// The label step is what a real source sees: for a source moved sideways by B, the disparity
// between the two middle labels' points of the reference's axis is the step times B over their
// mean depth (the angle the baseline subtends there), exactly for a sideways translation. It
// grows with the image's size and shrinks with more labels.
TEST(StereoGeometry, LabelStepIsTheDisparityOfOneLabelPerRadian) {
  const StereoCamera ref = LookAtCamera({0, 0, 0}, {0, 0, 1}, 700, 640, 480);
  for (bool inverse : {true, false}) {
    const DepthLabels labels(0.4, 0.9, 128, inverse);
    const double step = LabelStepPxPerRadian(ref, labels);
    const double near = labels.Depth(63.5), far = labels.Depth(64.5);
    for (double baseline : {0.02, 0.1}) {
      const StereoCamera src = LookAtCamera({baseline, 0, 0}, {baseline, 0, 1}, 700, 640, 480);
      auto project = [&](double depth) -> Eigen::Vector2d {
        return (src.K * (src.R * Eigen::Vector3d(0, 0, depth) + src.t)).hnormalized();
      };
      EXPECT_NEAR((project(near) - project(far)).norm(),
                  step * baseline / (0.5 * (near + far)), 1e-9 * step)
          << inverse << " " << baseline;
    }
    EXPECT_NEAR(LabelStepPxPerRadian(ref.Scaled(1280, 960), labels), 2 * step, 1e-9 * step);
    EXPECT_LT(LabelStepPxPerRadian(ref, DepthLabels(0.4, 0.9, 256, inverse)), 0.51 * step);
  }
}

// A source twice as far from the point, or with half the focal length, images it at half the
// scale; one looking at it from the side at the same distance, at the same scale.
TEST(StereoGeometry, ImageScaleRatioComparesEachCamerasPixelsAtThePoint) {
  const StereoCamera ref = LookAtCamera({0, 0, 0}, {0, 0, 1}, 700, 640, 480);
  EXPECT_NEAR(ImageScaleRatio(ref, ref, 1.0), 1.0, 1e-12);
  EXPECT_NEAR(ImageScaleRatio(ref, LookAtCamera({0, 0, -1}, {0, 0, 1}, 700, 640, 480), 1.0),
              0.5, 1e-12);
  EXPECT_NEAR(ImageScaleRatio(ref, LookAtCamera({0, 0, 0}, {0, 0, 1}, 350, 320, 240), 1.0), 0.5,
              1e-12);
  EXPECT_NEAR(ImageScaleRatio(ref, ref.Scaled(1280, 960), 1.0), 2.0, 1e-12);
  const StereoCamera side = LookAtCamera({1, 0, 1}, {0, 0, 1}, 700, 640, 480);
  EXPECT_NEAR(ImageScaleRatio(ref, side, 1.0), 1.0, 1e-12);
  // Behind the source: no scale.
  EXPECT_EQ(ImageScaleRatio(ref, LookAtCamera({0, 0, 2}, {0, 0, 3}, 700, 640, 480), 1.0), 0.0);
  // Beside the axis, looking along it: the z-depth counts (1 m), not the distance (1.118 m).
  const StereoCamera parallel = LookAtCamera({0.5, 0, 0}, {0.5, 0, 1}, 700, 640, 480);
  EXPECT_NEAR(ImageScaleRatio(ref, parallel, 1.0), 1.0, 1e-12);
}

// A camera ahead or behind has its epipole in the image; one beside, off it (or at infinity).
TEST(StereoGeometry, EpipoleInImageOfACameraAheadOrBehind) {
  const StereoCamera ref = LookAtCamera({0, 0, 0}, {0, 0, 1}, 700, 640, 480);
  EXPECT_TRUE(EpipoleInImage(ref, {0.01, 0, 0.3}));
  EXPECT_TRUE(EpipoleInImage(ref, {0, 0.02, -0.5}));
  EXPECT_FALSE(EpipoleInImage(ref, {0.3, 0, 0}));   // at infinity
  EXPECT_FALSE(EpipoleInImage(ref, {0.3, 0, 0.1}));  // 2100 px off the principal point
  const Eigen::Vector2d e = Epipole(ref, {0.01, 0, 0.3}).hnormalized();
  EXPECT_NEAR(std::abs(e.x() - 320), 700 * 0.01 / 0.3, 1e-9);
  EXPECT_NEAR(e.y(), 240, 1e-9);
}

// A strand in the fronto-parallel plane of the reference, seen from a source that is rolled,
// above and to the side (no pure roll about the baseline): TransferDirection gives its
// direction in the source exactly, where the epipole roll is only an approximation.
TEST(StereoGeometry, PlaneHomographyCarriesAStrandDirectionIntoTheSource) {
  const StereoCamera ref = LookAtCamera({0, 0, 0}, {0, 0, 1}, 100, 96, 72);
  const StereoCamera src = LookAtCamera({0.45, -0.35, 0.15}, {0, 0, 1}, 120, 96, 72, 0.3);
  const ViewProjection proj =
      ComputeViewProjection(ref, src, OrientationTransfer::kPlaneHomography);
  EXPECT_TRUE(proj.plane_homography);
  EXPECT_EQ(proj.Packed(1.0f)[14], 1.0f);
  auto image_point = [](const StereoCamera& c, const Eigen::Vector3d& p) {
    return Eigen::Vector2d((c.K * (c.R * p + c.t)).hnormalized());
  };
  double worst_roll_error = 0;
  for (double angle : {0.0, 0.4, 1.1, 1.9, 2.8}) {
    const Eigen::Vector3d a(0.07, -0.04, 1.0);
    const Eigen::Vector3d b = a + 1e-4 * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0);
    const Eigen::Vector2d in_ref = image_point(ref, b) - image_point(ref, a);
    const Eigen::Vector2d in_src = image_point(src, b) - image_point(src, a);
    const Eigen::Vector2d x = image_point(ref, a);
    const Eigen::Vector2d got = TransferDirection(proj, 1.0, x.x(), x.y(), in_ref.normalized());
    // The same line: the directions agree up to sign and a positive scale.
    const double sine =
        (got.x() * in_src.y() - got.y() * in_src.x()) / (got.norm() * in_src.norm());
    EXPECT_NEAR(sine, 0.0, 1e-3) << "angle " << angle;
    const double theta_ref = std::atan2(in_ref.y(), in_ref.x());
    const double theta_src = std::atan2(in_src.y(), in_src.x());
    const ViewProjection roll =
        ComputeViewProjection(ref, src, OrientationTransfer::kEpipoleRoll);
    worst_roll_error = std::max(
        worst_roll_error, 1.0 - std::cos(2 * (theta_src - theta_ref) + roll.psi_rad));
  }
  // The roll alone misses here (1 - cos of the doubled angle error > 0.01: > 3 degrees).
  EXPECT_GT(worst_roll_error, 0.01);
}

// A strand in a plane tilted 50 degrees towards the source (as hair on the side of a head):
// given the gradient of the plane's log depth, TransferDirection gives its direction in the
// source; taken as fronto-parallel, it misses.
TEST(StereoGeometry, TiltedPlaneCarriesAStrandDirectionIntoTheSource) {
  const StereoCamera ref = LookAtCamera({0, 0, 0}, {0, 0, 1}, 100, 96, 72);
  const StereoCamera src = LookAtCamera({0.5, -0.1, 0.1}, {0, 0, 1}, 100, 96, 72, 0.1);
  const ViewProjection proj =
      ComputeViewProjection(ref, src, OrientationTransfer::kPlaneHomography);
  auto image_point = [](const StereoCamera& c, const Eigen::Vector3d& p) {
    return Eigen::Vector2d((c.K * (c.R * p + c.t)).hnormalized());
  };
  const double tilt = 50 * M_PI / 180;
  const Eigen::Vector3d a(0.07, -0.04, 1.0);
  const Eigen::Vector3d normal(std::sin(tilt), 0.2, -std::cos(tilt));
  const Eigen::Vector2d x = image_point(ref, a);
  // The plane's z-depth along the ray of image point p (in the reference's frame), and its log
  // gradient at x.
  const Eigen::Vector3d a_ref = ref.R * a + ref.t, normal_ref = ref.R * normal;
  auto plane_depth = [&](const Eigen::Vector2d& p) {
    const Eigen::Vector3d ray = ref.K.inverse() * p.homogeneous();
    return normal_ref.dot(a_ref) / normal_ref.dot(ray);
  };
  const double h = 1e-3;
  const Eigen::Vector2d gradient(
      (std::log(plane_depth(x + Eigen::Vector2d(h, 0))) -
       std::log(plane_depth(x - Eigen::Vector2d(h, 0)))) / (2 * h),
      (std::log(plane_depth(x + Eigen::Vector2d(0, h))) -
       std::log(plane_depth(x - Eigen::Vector2d(0, h)))) / (2 * h));
  const Eigen::Vector3d u = normal.unitOrthogonal(), v = normal.cross(u).normalized();
  double worst_fronto_parallel_sine = 0;
  for (double angle : {0.0, 0.5, 1.2, 2.0, 2.7}) {
    const Eigen::Vector3d b = a + 1e-4 * (std::cos(angle) * u + std::sin(angle) * v);
    const Eigen::Vector2d in_ref = image_point(ref, b) - image_point(ref, a);
    const Eigen::Vector2d in_src = image_point(src, b) - image_point(src, a);
    auto sine = [&](const Eigen::Vector2d& got) {
      return std::abs(got.x() * in_src.y() - got.y() * in_src.x()) /
             (got.norm() * in_src.norm());
    };
    EXPECT_NEAR(
        sine(TransferDirection(proj, a_ref.z(), x.x(), x.y(), in_ref.normalized(), gradient)),
        0.0,
        1e-3)
        << "angle " << angle;
    worst_fronto_parallel_sine = std::max(
        worst_fronto_parallel_sine,
        sine(TransferDirection(proj, a_ref.z(), x.x(), x.y(), in_ref.normalized())));
  }
  EXPECT_GT(worst_fronto_parallel_sine, 0.1);  // more than 6 degrees off
}

// LogDepthGradient on the depth map of a tilted plane (odd size): the plane's gradient of log
// depth at levels 0 and 1 (twice as large per level-1 pixel), clamped for a steep one, and 0
// next to a pixel without depth.
TEST(StereoGeometry, LogDepthGradientOfAPlane) {
  const int width = 33, height = 21;
  const double focal = 40;
  const StereoCamera camera = LookAtCamera({0, 0, 0}, {0, 0, 1}, focal, width, height);
  // The plane n . X = 1 (camera frame): z(p) = 1 / (n . K^-1 p).
  auto depth_map = [&](const Eigen::Vector3d& n) {
    FloatMap depth(width, height, 1);
    for (int r = 0; r < height; ++r) {
      for (int c = 0; c < width; ++c) {
        depth.At(r, c) = static_cast<float>(
            1.0 / n.dot(camera.K.inverse() * Eigen::Vector3d(c + 0.5, r + 0.5, 1.0)));
      }
    }
    return depth;
  };
  // d log z / dp = -(n . K^-1 e) / (n . K^-1 p) for the image axes e.
  auto expected = [&](const Eigen::Vector3d& n, double x, double y) {
    const double denominator = n.dot(camera.K.inverse() * Eigen::Vector3d(x, y, 1.0));
    return Eigen::Vector2d(-n.x() / focal / denominator, -n.y() / focal / denominator);
  };
  const Eigen::Vector3d gentle(0.3, -0.2, 1.0);  // about 20 degrees
  const FloatMap depth = depth_map(gentle);
  const FloatMap level0 = LogDepthGradient(depth, 0, width, height, focal, focal, 70);
  const Eigen::Vector2d g0 = expected(gentle, 16.5, 10.5);
  EXPECT_NEAR(level0.At(10, 16, 0), g0.x(), 1e-3 * g0.norm());
  EXPECT_NEAR(level0.At(10, 16, 1), g0.y(), 1e-3 * g0.norm());
  EXPECT_EQ(level0.At(1, 16, 0), 0.0f);  // 2 px from the top: no pixel above
  // Level 1 (17 x 11): level pixel (5, 8) is nearest level-0 pixel (11, 17).
  const FloatMap level1 = LogDepthGradient(depth, 1, 17, 11, focal, focal, 70);
  const Eigen::Vector2d g1 = 2 * expected(gentle, 17.5, 11.5);
  EXPECT_NEAR(level1.At(5, 8, 0), g1.x(), 1e-3 * g1.norm());
  EXPECT_NEAR(level1.At(5, 8, 1), g1.y(), 1e-3 * g1.norm());
  // A plane at about 79 degrees on the optical axis: clamped at tan(70 degrees) / focal, its
  // direction kept.
  const Eigen::Vector3d steep(5.0, 0.0, 1.0);
  const FloatMap clamped = LogDepthGradient(depth_map(steep), 0, width, height, focal, focal, 70);
  EXPECT_NEAR(clamped.At(10, 17, 0), -std::tan(70 * M_PI / 180) / focal, 1e-6);
  EXPECT_NEAR(clamped.At(10, 17, 1), 0.0, 1e-6);
  // Pixels half as tall as wide (fy = 2 fx): a gradient per pixel in y is a tilt's tangent twice
  // what it is in x, so the clamp is in y's focal length (in x's, the -0.125 here would be
  // clamped to tan(70 degrees) / fx, a gradient twice as large: a tangent of 5.5 in y, 80
  // degrees).
  const Eigen::Vector3d steep_in_y(0.0, 5.0, 1.0);
  const FloatMap tall = LogDepthGradient(depth_map(steep_in_y), 0, width, height, focal,
                                         2 * focal, 70);
  EXPECT_NEAR(tall.At(10, 16, 0), 0.0, 1e-6);
  EXPECT_NEAR(tall.At(10, 16, 1), -std::tan(70 * M_PI / 180) / (2 * focal), 1e-6);
  // A hole: the pixels 2 px away in x and y have no gradient.
  FloatMap holed = depth;
  holed.At(10, 16) = 0;
  const FloatMap around_hole = LogDepthGradient(holed, 0, width, height, focal, focal, 70);
  EXPECT_EQ(around_hole.At(10, 14, 0), 0.0f);
  EXPECT_EQ(around_hole.At(12, 16, 1), 0.0f);
  EXPECT_NE(around_hole.At(11, 15, 0), 0.0f);
}

// An odd-sized image: a bright pixel goes through the box pyramid (DownsampleHalf, as the
// orientation fields' levels are made) and lands where PyramidLevel projects its point, which
// the size ratio (Scaled) misses by a pixel at level 2.
TEST(StereoGeometry, PyramidLevelCamerasFollowTheBoxPyramid) {
  const StereoCamera camera = LookAtCamera({0, 0, 0}, {0, 0, 1}, 40, 33, 21);
  const Eigen::Vector2d bright(30.5, 19.5);  // pixel (30, 19)
  const Eigen::Vector3d point =
      camera.R.transpose() * (camera.K.inverse() * Eigen::Vector3d(bright.x(), bright.y(), 1.0) -
                              camera.t);
  FloatMap image(33, 21, 1, 0.0f);
  image.At(19, 30, 0) = 1.0f;
  FloatMap level = image;
  for (int l = 1; l <= 2; ++l) {
    level = DownsampleHalf(level);
    const StereoCamera level_camera = camera.PyramidLevel(l);
    EXPECT_EQ(level_camera.width, level.Width());
    EXPECT_EQ(level_camera.height, level.Height());
    int best_col = 0, best_row = 0;
    for (int row = 0; row < level.Height(); ++row) {
      for (int col = 0; col < level.Width(); ++col) {
        if (level.At(row, col, 0) > level.At(best_row, best_col, 0)) best_col = col, best_row = row;
      }
    }
    const Eigen::Vector2d projected =
        (level_camera.K * (level_camera.R * point + level_camera.t)).hnormalized();
    EXPECT_EQ(static_cast<int>(std::floor(projected.x())), best_col) << "level " << l;
    EXPECT_EQ(static_cast<int>(std::floor(projected.y())), best_row) << "level " << l;
  }
  const StereoCamera by_ratio = camera.Scaled(9, 6);  // level 2's size, the extent kept
  const Eigen::Vector2d off = (by_ratio.K * (by_ratio.R * point + by_ratio.t)).hnormalized();
  EXPECT_EQ(static_cast<int>(std::floor(off.x())), 8);
  EXPECT_EQ(static_cast<int>(std::floor(off.y())), 5);
}

}  // namespace
}  // namespace hairmvs
