#include "src/core/depth_geometry.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

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
  FloatMap depth(9, 1, 1, 0.0f);
  // A single row has no vertical neighbour: no normal.
  depth.At(0, 4) = 1.0f;
  EXPECT_EQ(NormalMapFromDepthMap(depth, K).At(0, 4, 2), 0.0f);

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
  // An isolated pixel surrounded by a far background gets no normal.
  FloatMap spike(5, 5, 1, 3.0f);
  spike.At(2, 2) = 1.0f;
  EXPECT_EQ(NormalMapFromDepthMap(spike, K).At(2, 2, 2), 0.0f);
}

}  // namespace
}  // namespace hairmvs
