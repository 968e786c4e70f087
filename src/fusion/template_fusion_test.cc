#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <set>

#include "src/core/test_util.h"
#include "src/fusion/detail_transfer.h"
#include "src/fusion/fusion_points.h"
#include "src/fusion/fusion_test_scenes.h"
#include "src/fusion/template_fusion_core.h"

namespace hairmvs {
namespace {

struct SurfaceError {
  double mean = 0, max = 0, rms = 0;
};

SurfaceError ErrorToSurface(const testing::Sdf& sdf, const FusionMesh& mesh) {
  SurfaceError e;
  for (const Eigen::Vector3d& v : mesh.vertices) {
    const double d = testing::SurfaceDistance(sdf, v);
    e.mean += d;
    e.rms += d * d;
    e.max = std::max(e.max, d);
  }
  e.mean /= mesh.vertices.size();
  e.rms = std::sqrt(e.rms / mesh.vertices.size());
  return e;
}

int NumComponents(const FusionMesh& mesh) {
  int n = 0;
  mesh.FaceComponents(&n);
  return n;
}

TemplateFusionOptions TestOptions() {
  TemplateFusionOptions options;
  options.point_stride_px = 1;  // tiny maps: keep every pixel
  options.num_threads = 1;      // the tests run beside each other
  options.max_fit_vertices = 3000;  // a few seconds per test
  return options;
}

TEST(TemplateFusion, OptionsCheck) {
  TemplateFusionOptions options;
  std::string error;
  EXPECT_TRUE(options.Check(&error)) << error;
  options.poisson_depth = 1;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("poisson_depth"), std::string::npos);
  options = TemplateFusionOptions();
  options.input_type = "fancy";
  EXPECT_FALSE(options.Check(&error));
  // Bounds: a thread count that crashed OpenMP, rounds that ran for hours, a Poisson box or
  // voxel that leaves nothing to fuse, sizes that run out of memory after the maps are read.
  const std::vector<std::pair<std::function<void(TemplateFusionOptions*)>, std::string>> cases = {
      {[](TemplateFusionOptions* o) { o->num_threads = 257; }, "num_threads must be in [1, 256]"},
      {[](TemplateFusionOptions* o) { o->num_rounds = 101; }, "num_rounds must be in [0, 100]"},
      {[](TemplateFusionOptions* o) { o->poisson_scale = 4.5; }, "poisson_scale must be in [1, 4]"},
      {[](TemplateFusionOptions* o) { o->fused_voxel_size_px = 101; },
       "fused_voxel_size_px must be in (0, 100]"},
      // A mesh or a graph too large for memory, asked for by a tiny edge or node spacing.
      {[](TemplateFusionOptions* o) { o->max_mesh_vertices = 2000000000; },
       "max_mesh_vertices must be in [100, 2e7]"},
      {[](TemplateFusionOptions* o) { o->target_edge_length_px = 1e-6; },
       "target_edge_length_px must be >= 0.1"},
      {[](TemplateFusionOptions* o) { o->node_spacing_cells = 1e-9; },
       "node_spacing_cells must be in [0.25, 1000]"},
      {[](TemplateFusionOptions* o) { o->max_fit_vertices = 2000000000; },
       "max_fit_vertices must be in [1, 2e7]"},
      {[](TemplateFusionOptions* o) { o->max_solver_iterations = 100000; },
       "max_solver_iterations must be in [1, 1000]"}};
  for (const auto& [edit, expected] : cases) {
    options = TemplateFusionOptions();
    edit(&options);
    EXPECT_FALSE(options.Check(&error));
    EXPECT_NE(error.find(expected), std::string::npos) << error;
  }
}

TEST(TemplateFusion, PointsAreSeenByTheViewsThatAgree) {
  testing::SceneOptions scene;
  const std::vector<FusionView> views = testing::RenderViews(testing::SphereSdf(1.0), scene);
  TemplateFusionOptions options = TestOptions();
  int num_input = 0;
  const FusionPoints points = ExtractFusionPoints(views, options, &num_input);
  ASSERT_GT(points.Size(), 1000u);
  double max_error = 0;
  size_t num_multi_view = 0;
  for (size_t i = 0; i < points.Size(); ++i) {
    max_error = std::max(max_error, std::abs(points.xyz[i].cast<double>().norm() - 1.0));
    // The true normal of a sphere is radial.
    EXPECT_GT(points.normal[i].dot(points.xyz[i].normalized()), 0.95f);
    num_multi_view += points.visible_views[i].size() >= 3;
  }
  // Exact depths: points on the sphere up to the ray-marching tolerance.
  EXPECT_LT(max_error, 1e-4);
  // 12 views around a sphere: most points are seen by several.
  EXPECT_GT(num_multi_view, points.Size() / 2);
}

// Views held cropped to their depths (FusionView::CropToDepth, as RunTemplateFusion holds
// them) give the same points, bit for bit, at every stride (the crops' corners are not
// multiples of it), and the same depths along any line of sight.
TEST(TemplateFusion, ViewsCroppedToTheirDepthsGiveTheSamePoints) {
  testing::SceneOptions scene;
  std::vector<FusionView> whole = testing::RenderViews(testing::SphereSdf(1.0), scene);
  for (size_t v = 0; v < whole.size(); ++v) {
    FusionView& view = whole[v];
    // A colour per pixel, so that a shifted read shows.
    view.rgb = FloatMap(view.depth.Width(), view.depth.Height(), 3);
    for (size_t i = 0; i < view.rgb.Data().size(); ++i) view.rgb.Data()[i] = (i % 251) / 250.0f;
    // Each view's box its own (the sphere's alone is the same in every view): a view's reads
    // through another's offset would show.
    for (int row = 0; row < view.depth.Height(); ++row) {
      for (int col = 0; col < view.depth.Width(); ++col) {
        if (row < 14 + 2 * static_cast<int>(v) || col < 26 + static_cast<int>(v)) {
          view.depth.At(row, col) = 0.0f;
        }
      }
    }
  }
  std::vector<FusionView> cropped = whole;
  std::set<std::pair<int, int>> corners;
  int num_odd_corners = 0;
  for (FusionView& view : cropped) {
    view.CropToDepth();
    EXPECT_GT(view.col0 + view.row0, 0);
    EXPECT_LT(view.depth.NumPixels(), view.whole_width * view.whole_height);
    corners.insert({view.col0, view.row0});
    num_odd_corners += view.col0 % 2 + view.row0 % 2;
  }
  EXPECT_EQ(corners.size(), cropped.size());
  EXPECT_GT(num_odd_corners, 0);
  for (const int stride : {1, 2, 3}) {
    TemplateFusionOptions options = TestOptions();
    options.point_stride_px = stride;
    int num_whole = 0, num_cropped = 0;
    const FusionPoints from_whole = ExtractFusionPoints(whole, options, &num_whole);
    const FusionPoints from_cropped = ExtractFusionPoints(cropped, options, &num_cropped);
    ASSERT_GT(from_whole.Size(), 100u) << stride;
    EXPECT_EQ(num_cropped, num_whole) << stride;
    ASSERT_EQ(from_cropped.Size(), from_whole.Size()) << stride;
    for (size_t i = 0; i < from_whole.Size(); ++i) {
      ASSERT_EQ(from_cropped.xyz[i], from_whole.xyz[i]) << stride << " " << i;
      ASSERT_EQ(from_cropped.normal[i], from_whole.normal[i]) << stride << " " << i;
      ASSERT_EQ(from_cropped.rgb[i], from_whole.rgb[i]) << stride << " " << i;
      ASSERT_EQ(from_cropped.visible_views[i], from_whole.visible_views[i]) << stride << " " << i;
    }
  }
  EXPECT_EQ(MedianPixelFootprint(cropped), MedianPixelFootprint(whole));
  // Lines of sight through points on, in front of and behind the sphere, and beside it.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coordinate(-1.3, 1.3);
  int num_seen = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d world(coordinate(rng), coordinate(rng), coordinate(rng));
    for (size_t v = 0; v < whole.size(); ++v) {
      double z_whole = 0, z_cropped = 0, depth_whole = 0, depth_cropped = 0;
      const bool on_whole = whole[v].DepthOnRay(world, &z_whole, &depth_whole);
      ASSERT_EQ(cropped[v].DepthOnRay(world, &z_cropped, &depth_cropped), on_whole);
      EXPECT_EQ(depth_cropped, depth_whole);
      num_seen += on_whole;
      int col_whole, row_whole, col_cropped, row_cropped;
      if (whole[v].Project(world, &col_whole, &row_whole, &z_whole) &&
          whole[v].depth.At(row_whole, col_whole) > 0) {
        ASSERT_TRUE(cropped[v].Project(world, &col_cropped, &row_cropped, &z_cropped));
        EXPECT_EQ(col_cropped + cropped[v].col0, col_whole);
        EXPECT_EQ(row_cropped + cropped[v].row0, row_whole);
        EXPECT_EQ(cropped[v].BackProject(col_cropped, row_cropped, 0.7),
                  whole[v].BackProject(col_whole, row_whole, 0.7));
      }
    }
  }
  EXPECT_GT(num_seen, 1000);
}

// Every view twice, once with its normals turned around: each voxel's normals cancel and the
// merge keeps nothing, which is an error that says so (it was a failed CHECK in the Poisson
// grid's cell size).
TEST(TemplateFusion, NormalsThatCancelOutAreAnError) {
  testing::SceneOptions scene;
  std::vector<FusionView> views = testing::RenderViews(testing::SphereSdf(1.0), scene);
  const size_t num_views = views.size();
  for (size_t i = 0; i < num_views; ++i) {
    FusionView turned = views[i];
    if (turned.normal.Empty()) continue;
    for (float& v : turned.normal.Data()) v = -v;
    views.push_back(turned);
  }
  ASSERT_EQ(views.size(), 2 * num_views) << "the scene's views carry no normal maps";
  const std::string error =
      testing_util::ErrorOf([&] { FuseViews(views, TestOptions(), nullptr); });
  EXPECT_NE(error.find("the depth maps' normals cancel out"), std::string::npos) << error;
}

// Exact, aligned depth maps: the Poisson template already lies on the sphere, and the
// refinement and the detail must keep it there. Each view's depth is read where a vertex
// projects, between the pixel centres: the depth of the pixel it lands in, taken along the
// vertex's own ray up to half a pixel away, moved vertices along the slope on the sphere's
// flanks (mean error 0.00025 -> 0.0026 -> 0.0033, max 0.026, before SampleDepthMap).
TEST(TemplateFusion, ExactSphereStaysOnTheSurface) {
  testing::SceneOptions scene;
  const testing::Sdf sdf = testing::SphereSdf(1.0);
  const std::vector<FusionView> views = testing::RenderViews(sdf, scene);
  const FusionOutput out = FuseViews(views, TestOptions(), nullptr);
  const SurfaceError coarse = ErrorToSurface(sdf, out.coarse);
  const SurfaceError refined = ErrorToSurface(sdf, out.refined);
  const SurfaceError final_error = ErrorToSurface(sdf, out.final_mesh);
  std::cerr << "exact sphere error (mean/max): coarse " << coarse.mean << "/" << coarse.max
            << ", refined " << refined.mean << "/" << refined.max << ", final "
            << final_error.mean << "/" << final_error.max << "\n";
  EXPECT_LT(refined.mean, 0.002);
  EXPECT_LT(final_error.mean, 0.001);
  EXPECT_LT(final_error.max, 0.005);
}

TEST(TemplateFusion, NoisyMisalignedSphereIsOneGenusZeroSurface) {
  testing::SceneOptions scene;
  scene.depth_noise = 0.005;
  scene.misalignment_rad = 0.002;
  scene.misalignment_translation = 0.005;
  const testing::Sdf sdf = testing::SphereSdf(1.0);
  const std::vector<FusionView> views = testing::RenderViews(sdf, scene);
  StageTimings timings;
  const FusionOutput out = FuseViews(views, TestOptions(), &timings);
  std::cerr << timings.Table() << "\n";
  EXPECT_EQ(NumComponents(out.final_mesh), 1);
  EXPECT_EQ(out.final_mesh.EulerCharacteristic(), 2);  // genus 0
  const SurfaceError coarse = ErrorToSurface(sdf, out.coarse);
  const SurfaceError refined = ErrorToSurface(sdf, out.refined);
  const SurfaceError final_error = ErrorToSurface(sdf, out.final_mesh);
  std::cerr << "sphere error (mean/rms/max): coarse " << coarse.mean << "/" << coarse.rms << "/"
            << coarse.max << ", refined " << refined.mean << "/" << refined.rms << "/"
            << refined.max << ", final " << final_error.mean << "/" << final_error.rms << "/"
            << final_error.max << "\n";
  // Radius 1, depth noise 0.005, poses off by ~0.1 degree and 0.005: within 1.5% of the
  // radius on average and 6% at worst.
  EXPECT_LT(final_error.mean, 0.015);
  EXPECT_LT(final_error.max, 0.06);
}

TEST(TemplateFusion, NoisyMisalignedTorusIsOneGenusOneSurface) {
  testing::SceneOptions scene;
  scene.depth_noise = 0.005;
  scene.misalignment_rad = 0.002;
  scene.misalignment_translation = 0.005;
  const testing::Sdf sdf = testing::TorusSdf(1.0, 0.4);
  const std::vector<FusionView> views = testing::RenderViews(sdf, scene);
  const FusionOutput out = FuseViews(views, TestOptions(), nullptr);
  EXPECT_EQ(NumComponents(out.final_mesh), 1);
  EXPECT_EQ(out.final_mesh.EulerCharacteristic(), 0);  // genus 1
  const SurfaceError final_error = ErrorToSurface(sdf, out.final_mesh);
  std::cerr << "torus error (mean/rms/max): " << final_error.mean << "/" << final_error.rms
            << "/" << final_error.max << "\n";
  EXPECT_LT(final_error.mean, 0.02);
  EXPECT_LT(final_error.max, 0.1);
}

TEST(TemplateFusion, DetailRestoresHighFrequencies) {
  testing::SceneOptions scene;
  scene.width = 128;
  scene.height = 96;
  scene.focal_px = 120;  // pixel footprint ~0.033 at the sphere
  scene.depth_noise = 0.001;
  // Ripples of +-0.02 with a period of ~0.2: finer than a coarse template at octree depth 5
  // (cell ~0.07) and its deformation graph can hold, coarser than the depth maps' pixels.
  const testing::Sdf sdf = testing::RippledSphereSdf(1.0, 0.02, 30);
  const std::vector<FusionView> views = testing::RenderViews(sdf, scene);
  TemplateFusionOptions options = TestOptions();
  options.poisson_depth = 5;
  options.target_edge_length_px = 1.5;  // vertices dense enough to carry the ripples
  const FusionOutput out = FuseViews(views, options, nullptr);
  const SurfaceError refined = ErrorToSurface(sdf, out.refined);
  const SurfaceError final_error = ErrorToSurface(sdf, out.final_mesh);
  std::cerr << "rippled sphere rms: refined " << refined.rms << ", after detail "
            << final_error.rms << " (" << out.final_mesh.vertices.size() << " vertices)\n";
  EXPECT_GT(out.detail.num_vertices_with_detail,
            static_cast<int>(out.final_mesh.vertices.size() / 2));
  EXPECT_LT(final_error.rms, 0.7 * refined.rms);
}

// The detail's linear least-squares offsets (detail_smoothness_weight): on a grid of 6 x 4
// vertices with targets on some, the result satisfies the problem's normal equations, those
// without a target take values between their neighbours' (the maximum principle: not 0), and a
// separate part of the mesh without any target stays NaN.
TEST(TemplateFusion, SmoothDetailOffsetsSolvesTheLeastSquaresProblem) {
  FusionMesh mesh;
  const int cols = 6, rows = 4;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) mesh.vertices.emplace_back(c, r, 0);
  }
  for (int r = 0; r + 1 < rows; ++r) {
    for (int c = 0; c + 1 < cols; ++c) {
      const int v = r * cols + c;
      mesh.faces.emplace_back(v, v + 1, v + cols + 1);
      mesh.faces.emplace_back(v, v + cols + 1, v + cols);
    }
  }
  // A lone triangle apart from the grid.
  const int lone = static_cast<int>(mesh.vertices.size());
  for (int k = 0; k < 3; ++k) mesh.vertices.emplace_back(10 + k, 10, 0);
  mesh.faces.emplace_back(lone, lone + 1, lone + 2);
  const double nan = std::nan("");
  std::vector<double> targets(mesh.vertices.size(), nan);
  for (int r = 0; r < rows; ++r) {
    targets[r * cols] = 0.001 * r;             // the left column
    targets[r * cols + cols - 1] = 0.004 + 0.001 * r;  // the right one
  }
  targets[2 * cols + 2] = 0.010;  // one inside, above both
  const double weight = 0.7;
  std::vector<double> offsets = targets;
  SmoothDetailOffsets(mesh, weight, &offsets);
  // The normal equations: w_i (s_i - t_i) + weight * sum over i's edges (s_i - s_j) = 0.
  std::vector<std::set<int>> neighbours(mesh.vertices.size());
  for (const Eigen::Vector3i& f : mesh.faces) {
    for (int k = 0; k < 3; ++k) {
      neighbours[f[k]].insert(f[(k + 1) % 3]);
      neighbours[f[(k + 1) % 3]].insert(f[k]);
    }
  }
  for (int i = 0; i < rows * cols; ++i) {
    double gradient = std::isnan(targets[i]) ? 0.0 : offsets[i] - targets[i];
    for (int j : neighbours[i]) gradient += weight * (offsets[i] - offsets[j]);
    EXPECT_NEAR(gradient, 0.0, 1e-9) << "vertex " << i;
    if (std::isnan(targets[i])) {
      double lo = 1, hi = -1;
      for (int j : neighbours[i]) {
        lo = std::min(lo, offsets[j]);
        hi = std::max(hi, offsets[j]);
      }
      EXPECT_GT(offsets[i], 0.0) << "vertex " << i;
      EXPECT_GE(offsets[i], lo - 1e-12) << "vertex " << i;
      EXPECT_LE(offsets[i], hi + 1e-12) << "vertex " << i;
    }
  }
  // A target is pulled towards its neighbours, not kept: the inner one lies above them all.
  EXPECT_LT(offsets[2 * cols + 2], 0.010);
  EXPECT_GT(offsets[2 * cols + 2], offsets[2 * cols + 1]);
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(std::isnan(offsets[lone + k]));
}

}  // namespace
}  // namespace hairmvs
