#include "src/evaluation/mesh_distance.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>

#include "colmap_ext/ply.h"
#include "src/core/test_util.h"

namespace hairmvs {
namespace {

// Dense sampling of the triangle: an upper bound that converges to the distance.
double SampledTriangleDistance(const Eigen::Vector3d& x, const Eigen::Vector3d& a,
                               const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  double best = std::numeric_limits<double>::infinity();
  const int m = 400;
  for (int i = 0; i <= m; ++i) {
    for (int j = 0; i + j <= m; ++j) {
      const Eigen::Vector3d p = a + (b - a) * (double(i) / m) + (c - a) * (double(j) / m);
      best = std::min(best, (p - x).norm());
    }
  }
  return best;
}

TEST(MeshDistance, PointTriangleDistanceMatchesSampling) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 30; ++k) {
    const Eigen::Vector3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)),
        c(u(rng), u(rng), u(rng)), x(2 * u(rng), 2 * u(rng), 2 * u(rng));
    const double exact = PointTriangleDistance(x, a, b, c);
    const double sampled = SampledTriangleDistance(x, a, b, c);
    EXPECT_LE(exact, sampled + 1e-12);
    EXPECT_NEAR(exact, sampled, 1e-2);  // the sampling's resolution (edges <= ~3.5 / 400)
  }
  // Simple cases: above the interior, beyond a vertex, a degenerate triangle.
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_DOUBLE_EQ(PointTriangleDistance(Eigen::Vector3d(0.2, 0.2, 0.5), a, b, c), 0.5);
  EXPECT_DOUBLE_EQ(PointTriangleDistance(Eigen::Vector3d(2, 0, 0), a, b, c), 1.0);
  EXPECT_NEAR(PointTriangleDistance(Eigen::Vector3d(0.5, 1, 0), a, b, Eigen::Vector3d(2, 0, 0)),
              1.0, 1e-12);
}

TriangleMesh TestMesh() {
  // A wavy height field, 21 x 21 vertices over 4 cm x 4 cm.
  TriangleMesh mesh;
  const int n = 21;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const float x = 0.002f * i, y = 0.002f * j;
      mesh.vertices.emplace_back(x, y, 0.004f * std::sin(150 * x) * std::cos(100 * y));
    }
  }
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = 0; j + 1 < n; ++j) {
      const int v = i * n + j;
      mesh.faces.emplace_back(v, v + 1, v + n);
      mesh.faces.emplace_back(v + 1, v + n + 1, v + n);
    }
  }
  return mesh;
}

TEST(MeshDistance, KdTreeQueriesMatchBruteForce) {
  const TriangleMesh mesh = TestMesh();
  const TriangleMeshDistance distance(mesh, 1e-3);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.01, 0.05);
  std::vector<Eigen::Vector3d> queries;
  for (int k = 0; k < 200; ++k) queries.emplace_back(u(rng), u(rng), 0.2 * u(rng));
  const std::vector<double> batch = distance.Distances(queries);
  for (size_t k = 0; k < queries.size(); ++k) {
    double brute = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3i& f : mesh.faces) {
      brute = std::min(brute, PointTriangleDistance(queries[k], mesh.vertices[f(0)].cast<double>(),
                                                    mesh.vertices[f(1)].cast<double>(),
                                                    mesh.vertices[f(2)].cast<double>()));
    }
    EXPECT_NEAR(batch[k], brute, 1e-9) << k;
  }
}

TEST(MeshDistance, SurfaceSamplesFollowTheArea) {
  TriangleMesh square;
  square.vertices = {{0, 0, 0}, {0.01f, 0, 0}, {0.01f, 0.01f, 0}, {0, 0.01f, 0}};
  square.faces = {{0, 1, 2}, {0, 2, 3}};
  std::mt19937 rng(1);
  const auto samples = SampleMeshSurface(square, 1e-4, &rng);  // 1 cm^2 / 0.01 mm^2
  EXPECT_NEAR(static_cast<double>(samples.size()), 10000.0, 2.0);
  for (const Eigen::Vector3d& p : samples) {
    EXPECT_GE(p.x(), -1e-9);
    EXPECT_LE(p.x(), 0.01 + 1e-9);
    EXPECT_NEAR(p.z(), 0.0, 1e-12);
  }
  // A spacing too fine for memory (1e12 samples of 1 cm^2) is an error, not an overflow.
  const std::string error = testing_util::ErrorOf([&] { SampleMeshSurface(square, 1e-8, &rng); });
  EXPECT_NE(error.find("use a larger sample spacing"), std::string::npos) << error;
}

// The same for the index of the mesh's surface: the count is known before the samples are made
// (1e12 here), so the error comes at once, not after the memory is full.
TEST(MeshDistance, IndexTooFineForMemoryIsAnError) {
  TriangleMesh square;
  square.vertices = {{0, 0, 0}, {0.01f, 0, 0}, {0.01f, 0.01f, 0}, {0, 0.01f, 0}};
  square.faces = {{0, 1, 2}, {0, 2, 3}};
  const std::string error = testing_util::ErrorOf([&] { TriangleMeshDistance(square, 1e-8); });
  EXPECT_NE(error.find("every 1e-08 m would take"), std::string::npos) << error;
  EXPECT_NE(error.find("use a larger sample spacing"), std::string::npos) << error;
}

}  // namespace
}  // namespace hairmvs
