#include "src/core/depth_geometry.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <utility>
#include <vector>

#include "src/core/test_util.h"

namespace hairmvs {
namespace {

Eigen::Matrix3d TestK() {
  Eigen::Matrix3d K;
  K << 100, 0, 32, 0, 110, 24, 0, 0, 1;
  return K;
}

TEST(DepthGeometry, BackProjectUsesPixelCentres) {
  const Eigen::Matrix3d K = TestK();
  // Pixel (31.5, 23.5) + 0.5 is the principal point: on the optical axis.
  EXPECT_TRUE(BackProjectPixel(K, 31.5, 23.5, 2.0).isApprox(Eigen::Vector3d(0, 0, 2)));
  const Eigen::Vector3d X = BackProjectPixel(K, 10, 5, 1.5);
  const Eigen::Vector3d x = K * X;
  EXPECT_NEAR(x(0) / x(2), 10.5, 1e-12);
  EXPECT_NEAR(x(1) / x(2), 5.5, 1e-12);
  EXPECT_DOUBLE_EQ(X(2), 1.5);
}

// COLMAP's max_image_size: the longer side scaled to it and rounded, the intrinsics with it.
TEST(DepthGeometry, AtMaxImageSizeFollowsColmapsRule) {
  StereoCamera camera;
  camera.K << 767.783, 0, 480, 0, 767.783, 320, 0, 0, 1;
  camera.width = 960;
  camera.height = 640;
  const StereoCamera small = camera.AtMaxImageSize(320);
  EXPECT_EQ(small.width, 320);
  EXPECT_EQ(small.height, 213);  // 640 / 3 = 213.3
  EXPECT_NEAR(small.K(0, 0), 767.783 / 3, 1e-9);
  EXPECT_NEAR(small.K(1, 2), 320 * 213.0 / 640, 1e-9);
  for (const int unchanged : {-1, 0, 960, 2000}) {
    const StereoCamera same = camera.AtMaxImageSize(unchanged);
    EXPECT_EQ(same.width, 960) << unchanged;
    EXPECT_EQ(same.height, 640) << unchanged;
    EXPECT_EQ(same.K, camera.K) << unchanged;
  }
}

// A map at another scale (COLMAP's max_image_size) fits its image to a pixel's rounding each
// way; one of another aspect ratio does not, and is named.
TEST(DepthGeometry, MapsAtAnotherScaleFitTheirCamera) {
  EXPECT_TRUE(IsScaledCopy(960, 640, 960, 640));
  EXPECT_TRUE(IsScaledCopy(320, 213, 960, 640));
  EXPECT_TRUE(IsScaledCopy(320, 214, 960, 640));
  EXPECT_FALSE(IsScaledCopy(320, 216, 960, 640));
  EXPECT_FALSE(IsScaledCopy(640, 960, 960, 640));
  EXPECT_FALSE(IsScaledCopy(0, 640, 960, 640));
  StereoCamera camera;
  camera.width = 960;
  camera.height = 640;
  EXPECT_EQ(camera.ScaledToMap(480, 320, "m.bin").K(0, 0), 0.5);
  EXPECT_EQ(testing_util::ErrorOf([&] { camera.ScaledToMap(640, 960, "m.bin"); }),
            "m.bin is 640 x 960, another aspect ratio than its image's 960 x 640: a map of "
            "another view, or of another model");
}

// A camera's pixel round-trips through the world and back, on its own grid and on a scaled
// one (where the same world point lands at the scaled pixel centre's cell); off the grid and
// behind the camera it has no pixel.
TEST(DepthGeometry, StereoCameraProjectsWhatItBackProjects) {
  StereoCamera camera;
  camera.K = TestK();
  camera.R = Eigen::AngleAxisd(0.2, Eigen::Vector3d(0.3, 1, 0).normalized()).toRotationMatrix();
  camera.t = Eigen::Vector3d(0.05, -0.02, 0.6);
  camera.width = 64;
  camera.height = 48;
  EXPECT_TRUE(camera.Center().isApprox(-camera.R.transpose() * camera.t));
  for (const auto& [col, row] : {std::pair(0, 0), std::pair(63, 47), std::pair(17, 30)}) {
    const Eigen::Vector3d world = camera.BackProject(col, row, 0.8);
    int c = -1, r = -1;
    double z = 0;
    ASSERT_TRUE(camera.Project(world, &c, &r, &z));
    EXPECT_EQ(c, col);
    EXPECT_EQ(r, row);
    EXPECT_NEAR(z, 0.8, 1e-12);
    // Half the grid: pixel (col, row) lies in cell (col / 2, row / 2).
    ASSERT_TRUE(camera.Scaled(32, 24).Project(world, &c, &r, &z));
    EXPECT_EQ(c, col / 2);
    EXPECT_EQ(r, row / 2);
    EXPECT_NEAR(z, 0.8, 1e-12);
  }
  int c, r;
  double z;
  const Eigen::Vector3d centre_ray = camera.BackProject(31, 23, 1.0) - camera.Center();
  EXPECT_FALSE(camera.Project(camera.Center() - centre_ray, &c, &r, &z));  // behind
  EXPECT_FALSE(camera.Project(camera.BackProject(0, 0, 1.0) +
                                  camera.R.transpose() * Eigen::Vector3d(-0.1, 0, 0),
                              &c, &r, &z));  // left of the grid
}

// Depth of the plane n . X = c along the ray through pixel (col, row).
double PlaneDepth(const Eigen::Matrix3d& K, const Eigen::Vector3d& n, double c, int col,
                  int row) {
  const Eigen::Vector3d ray = BackProjectPixel(K, col, row, 1.0);
  return c / n.dot(ray);
}

TEST(DepthGeometry, NormalsOfATiltedPlane) {
  const Eigen::Matrix3d K = TestK();
  const int width = 64, height = 48;
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.2, -1.0).normalized();
  const double c = n.dot(Eigen::Vector3d(0, 0, 1.0));
  FloatMap depth(width, height, 1);
  for (int r = 0; r < height; ++r) {
    for (int col = 0; col < width; ++col) depth.At(r, col) = PlaneDepth(K, n, c, col, r);
  }
  // A hole: invalid pixel and its neighbours fall back to one-sided differences.
  depth.At(20, 20) = 0;
  const FloatMap normals = NormalMapFromDepthMap(depth, K);
  ASSERT_EQ(normals.Channels(), 3);
  for (int r = 0; r < height; ++r) {
    for (int col = 0; col < width; ++col) {
      const Eigen::Vector3d m(normals.At(r, col, 0), normals.At(r, col, 1), normals.At(r, col, 2));
      if (r == 20 && col == 20) {
        EXPECT_EQ(m.norm(), 0.0);
        continue;
      }
      // n faces the camera already (n_z < 0); float depths limit the accuracy.
      EXPECT_NEAR((m - n).norm(), 0.0, 2e-3) << r << " " << col;
    }
  }
}

TEST(DepthGeometry, NormalsFaceTheCameraAndStopAtDiscontinuities) {
  const Eigen::Matrix3d K = TestK();
  // A strand one pixel wide, along a row tilted in depth, has no vertical neighbour: its normal
  // is the one across the row's tangent that faces the camera most.
  FloatMap depth(9, 3, 1, 0.0f);
  for (int col = 0; col < 9; ++col) depth.At(1, col) = 1.0f + 0.01f * col;
  const FloatMap strand = NormalMapFromDepthMap(depth, K);
  for (int col = 0; col < 9; ++col) {
    const Eigen::Vector3d m(strand.At(1, col, 0), strand.At(1, col, 1), strand.At(1, col, 2));
    EXPECT_NEAR(m.norm(), 1.0, 1e-6) << col;
    const Eigen::Vector3d ray = BackProjectPixel(K, col, 1, depth.At(1, col)).normalized();
    EXPECT_LT(m.dot(ray), 0.0) << col;  // faces the camera
    // Perpendicular to the strand's tangent (between its neighbours, or one-sided at its ends).
    const int a = std::max(col - 1, 0), b = std::min(col + 1, 8);
    const Eigen::Vector3d along = BackProjectPixel(K, b, 1, depth.At(1, b)) -
                                  BackProjectPixel(K, a, 1, depth.At(1, a));
    EXPECT_NEAR(m.dot(along.normalized()), 0.0, 1e-5) << col;
    // Of the normals across it, the one nearest the reversed line of sight: in their plane.
    EXPECT_NEAR(m.dot(along.cross(ray).normalized()), 0.0, 1e-5) << col;
  }
  // Only invalid depths have no normal (COLMAP's fusion drops a depth whose normal is 0).
  for (int row : {0, 2}) {
    for (int col = 0; col < 9; ++col) {
      for (int k = 0; k < 3; ++k) EXPECT_EQ(strand.At(row, col, k), 0.0f);
    }
  }

  FloatMap step(12, 12, 1, 1.0f);
  for (int r = 0; r < 12; ++r) {
    for (int col = 6; col < 12; ++col) step.At(r, col) = 2.0f;  // 1 m jump: a discontinuity
  }
  const FloatMap normals = NormalMapFromDepthMap(step, K);
  for (int r = 0; r < 12; ++r) {
    for (int col = 0; col < 12; ++col) {
      // Fronto-parallel planes on both sides, also next to the jump (one-sided differences).
      const Eigen::Vector3d m(normals.At(r, col, 0), normals.At(r, col, 1), normals.At(r, col, 2));
      const Eigen::Vector3d expected(0, 0, -1);
      EXPECT_NEAR((m - expected).norm(), 0.0, 1e-5) << r << " " << col;
    }
  }
  // An isolated pixel in front of a far background faces the camera along its line of sight.
  FloatMap spike(5, 5, 1, 3.0f);
  spike.At(2, 2) = 1.0f;
  const FloatMap spike_normals = NormalMapFromDepthMap(spike, K);
  const Eigen::Vector3d m(spike_normals.At(2, 2, 0), spike_normals.At(2, 2, 1),
                          spike_normals.At(2, 2, 2));
  EXPECT_NEAR((m + BackProjectPixel(K, 2, 2, 1.0).normalized()).norm(), 0.0, 1e-6);
}

TEST(DepthGeometry, SampleDepthMapInterpolatesOneSurfaceOnly) {
  const double focal = 100;
  FloatMap ramp(12, 10, 1);
  for (int r = 0; r < 10; ++r) {
    for (int col = 0; col < 12; ++col) ramp.At(r, col) = 1.0f + 0.002f * col + 0.001f * r;
  }
  // Pixel centres at (col + 0.5, row + 0.5): bilinear is exact on a ramp.
  for (const auto& [x, y] : std::vector<std::pair<double, double>>{
           {3.5, 4.5}, {3.9, 4.2}, {7.01, 2.99}, {10.6, 8.4}}) {
    EXPECT_NEAR(SampleDepthMap(ramp, x, y, focal), 1.0 + 0.002 * (x - 0.5) + 0.001 * (y - 0.5),
                1e-6)
        << x << " " << y;
  }
  // Within half a pixel of the border there are not four centres around: the pixel's depth.
  EXPECT_FLOAT_EQ(SampleDepthMap(ramp, 0.2, 4.5, focal), ramp.At(4, 0));
  EXPECT_FLOAT_EQ(SampleDepthMap(ramp, 11.8, 9.9, focal), ramp.At(9, 11));
  // Off the map, or where the pixel has no depth: 0; a missing neighbour: the pixel's depth.
  EXPECT_EQ(SampleDepthMap(ramp, -0.1, 4.5, focal), 0.0);
  EXPECT_EQ(SampleDepthMap(ramp, 12.0, 4.5, focal), 0.0);
  FloatMap holed = ramp;
  holed.At(4, 4) = 0;
  EXPECT_EQ(SampleDepthMap(holed, 4.2, 4.7, focal), 0.0);
  EXPECT_FLOAT_EQ(SampleDepthMap(holed, 3.9, 4.7, focal), holed.At(4, 3));
  // A step between two layers (0.5 m, far steeper than max_slope): never blended.
  FloatMap step(12, 10, 1, 1.0f);
  for (int r = 0; r < 10; ++r) {
    for (int col = 6; col < 12; ++col) step.At(r, col) = 1.5f;
  }
  EXPECT_FLOAT_EQ(SampleDepthMap(step, 5.9, 4.5, focal), 1.0f);
  EXPECT_FLOAT_EQ(SampleDepthMap(step, 6.1, 4.5, focal), 1.5f);
}

}  // namespace
}  // namespace hairmvs
