#include "src/stereo/geometric_prior.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "src/opencl/opencl_context.h"
#include "src/stereo/stereo_test_util.h"

namespace hairmvs {
namespace {

using testing_util::PlaneView;

// The stereo camera of a view's depth map.
StereoCamera CameraOf(const FusionView& view) {
  StereoCamera camera;
  camera.K = view.K;
  camera.R = view.R;
  camera.t = view.t;
  camera.width = view.depth.Width();
  camera.height = view.depth.Height();
  return camera;
}

// The prior uses the consistency filter's forward-backward error: 0 at the depth the other
// views' maps agree with, the most where they disagree by the maximum error or do not see the
// point.
TEST(GeometricPriorTest, IsLowestAtTheDepthTheOtherMapsAgreeWith) {
  auto context = OpenCLContext::Create();
  const FusionView ref = PlaneView(Eigen::Vector3d(0, 0, 0), 0.0);
  const FusionView left = PlaneView(Eigen::Vector3d(-0.1, 0, 0), 0.1);
  FusionView blind = PlaneView(Eigen::Vector3d(0.1, 0, 0), -0.1);
  for (float& d : blind.depth.Data()) d = 0.0f;  // no depth anywhere
  const StereoCamera camera = CameraOf(ref);
  const DepthLabels labels(0.5, 2.0, 64, /*inverse=*/true);
  const size_t n = static_cast<size_t>(camera.width) * camera.height;
  GeometricPrior prior;
  prior.views = {&left, &blind};
  prior.weight = 2.0;
  prior.max_error_px = 3.0;
  std::vector<float> volume(n * labels.num_labels, 0.0f);
  GeometricPriorCL prior_cl(context.get(), prior);
  prior_cl.Add(camera, 1.0, labels, {}, 1.0f, labels.num_labels, {}, 0.5f, &volume);
  int checked = 0;
  for (int row = 0; row < camera.height; ++row) {
    for (int col = 20; col < 60; ++col) {  // the part of the reference the left view sees
      const size_t p = static_cast<size_t>(row) * camera.width + col;
      int best = 0;
      for (int k = 1; k < labels.num_labels; ++k) {
        if (volume[k * n + p] < volume[best * n + p]) best = k;
      }
      const double true_label = labels.Label(ref.depth.At(row, col));
      EXPECT_LE(std::abs(best - true_label), 1.0) << row << " " << col;
      // weight * scale = 1 over the two views: the blind one always adds 0.5, the left one
      // nearly nothing at the true depth and 0.5 at labels far from it.
      EXPECT_NEAR(volume[best * n + p], 0.5f, 0.1f);
      EXPECT_FLOAT_EQ(volume[0 * n + p], 1.0f);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 40 * 60);
  // Labels relative to a per-pixel base (the fine band) score the same depths alike.
  std::vector<float> base(n, 10.0f), band(n * 8, 0.0f);
  prior_cl.Add(camera, 1.0, labels, base, 0.5f, 8, {}, 0.5f, &band);
  for (int k = 0; k < 8; ++k) {
    const size_t p = 30 * camera.width + 40;
    std::vector<float> single(n, 0.0f);
    const std::vector<float> one_base(n, 10.0f + 0.5f * k);
    prior_cl.Add(camera, 1.0, labels, one_base, 1.0f, 1, {}, 0.5f, &single);
    EXPECT_NEAR(band[k * n + p], single[p], 1e-6f) << k;
  }
}


// The kernel against the plain double-precision reference on a coarse grid (2 level-0 pixels per
// grid pixel) with per-pixel label bases: maps that disagree with the reference by a few pixels
// (so that errors fall on both sides of max_error_px), holes, and a view that sees only part of
// the reference; with the bases, only at the pixels of a mask.
TEST(GeometricPriorTest, KernelMatchesTheCpuReference) {
  auto context = OpenCLContext::Create();
  const FusionView ref = PlaneView(Eigen::Vector3d(0, 0, 0), 0.0);
  // Off the reference's rows and depth, so that grid points do not project onto the sources'
  // pixel borders.
  // The fourth stands 0.7 m in front of the reference: the labels' points nearer than that lie
  // behind it.
  std::vector<FusionView> views = {PlaneView(Eigen::Vector3d(-0.1, 0.013, 0.02), 0.1),
                                   PlaneView(Eigen::Vector3d(0.1, 0.05, -0.01), -0.1),
                                   PlaneView(Eigen::Vector3d(0.3, -0.021, 0.005), 0.0),
                                   PlaneView(Eigen::Vector3d(0.05, 0.017, 0.7), 0.0)};
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> scale(0.9f, 1.1f), unit(0.0f, 1.0f);
  for (FusionView& view : views) {
    for (float& d : view.depth.Data()) d = unit(rng) < 0.1f ? 0.0f : d * scale(rng);
  }
  const StereoCamera grid = CameraOf(ref).PyramidLevel(1);
  const DepthLabels labels(0.5, 2.0, 64, /*inverse=*/true);
  const size_t n = static_cast<size_t>(grid.width) * grid.height;
  std::vector<float> base(n);
  for (float& b : base) b = 40.0f * unit(rng);
  GeometricPrior prior;
  for (const FusionView& view : views) prior.views.push_back(&view);
  prior.weight = 2.0;
  prior.max_error_px = 6.0;
  // More labels than a work-item takes (16 in kernels/geometric_prior.cl): a whole chunk and
  // a part of one.
  const int num_labels = 20;
  // A mask of the pixels where the prior is added (about two thirds), with the base only.
  std::vector<uint8_t> active(n);
  for (uint8_t& a : active) a = unit(rng) < 0.67f;
  // Labels uniform in inverse depth (the default) and in depth; with and without a base and a
  // mask, each on its own.
  const DepthLabels linear(0.5, 2.0, 64, /*inverse=*/false);
  for (int sampling_and_inputs = 0; sampling_and_inputs < 8; ++sampling_and_inputs) {
    const DepthLabels& sampling = sampling_and_inputs < 4 ? labels : linear;
    const bool with_base = sampling_and_inputs % 2 == 0;
    const bool with_mask = sampling_and_inputs % 4 < 2;
    const std::string what = std::string(sampling.inverse ? "inverse depth" : "depth") +
                             (with_base ? ", base" : "") + (with_mask ? ", mask" : "");
    const std::vector<float> label_base = with_base ? base : std::vector<float>();
    const std::vector<uint8_t> pixels = with_mask ? active : std::vector<uint8_t>();
    // Without a base: labels 0 to 55.1. (With 12 labels 5 apart, label 35's depth, 0.857 m,
    // put grid column 37 exactly on a pixel border of the third view, u = 40, in exact
    // arithmetic: a single-precision kernel then reads one side or the other of the whole
    // column.)
    const float step = with_base ? 0.75f : 2.9f;
    std::vector<float> expected(n * num_labels, 0.25f), got = expected;
    AddGeometricPriorCpu(prior, grid, 2.0, sampling, label_base, step, num_labels, pixels, 0.5f,
                         &expected);
    GeometricPriorCL(context.get(), prior)
        .Add(grid, 2.0, sampling, label_base, step, num_labels, pixels, 0.5f, &got);
    // Single precision moves a projection by about 1e-4 px: where that crosses a pixel border
    // of a source map, the two read neighbouring depths (a few entries in a million).
    size_t close = 0, partial = 0, untouched = 0, inactive = 0;
    for (size_t i = 0; i < got.size(); ++i) {
      if (std::abs(got[i] - expected[i]) < 1e-4f) ++close;
      // Neither all views at 0 nor all at the maximum: the entry measures real errors.
      if (expected[i] > 0.26f && expected[i] < 1.24f) ++partial;
      if (!pixels.empty() && pixels[i % n] == 0) {
        ++inactive;
        untouched += got[i] == 0.25f && expected[i] == 0.25f;
      }
    }
    EXPECT_GE(close, got.size() - got.size() / 1000) << what;
    EXPECT_GT(partial, got.size() / 5) << what;
    // Nothing added outside the mask.
    EXPECT_EQ(untouched, inactive) << what;
    if (with_mask) {
      EXPECT_GT(inactive, got.size() / 5) << what;
    }
  }
}

// Maps held cropped to their depths (FusionView::CropToDepth, as the geometric pass holds
// them) give the prior of the whole maps, bit for bit, in the kernel and in the reference.
TEST(GeometricPriorTest, MapsCroppedToTheirDepthsGiveTheSamePrior) {
  auto context = OpenCLContext::Create();
  const FusionView ref = PlaneView(Eigen::Vector3d(0, 0, 0), 0.0);
  std::vector<FusionView> whole = {PlaneView(Eigen::Vector3d(-0.1, 0.013, 0.02), 0.1),
                                   PlaneView(Eigen::Vector3d(0.1, 0.05, -0.01), -0.1)};
  // Depths only in a box off every edge, each map's own.
  const PixelBox boxes[] = {{7, 5, 50, 41}, {23, 12, 44, 37}};
  for (size_t v = 0; v < whole.size(); ++v) {
    const PixelBox& box = boxes[v];
    for (int row = 0; row < whole[v].depth.Height(); ++row) {
      for (int col = 0; col < whole[v].depth.Width(); ++col) {
        if (col < box.x0 || row < box.y0 || col >= box.x0 + box.width ||
            row >= box.y0 + box.height) {
          whole[v].depth.At(row, col) = 0.0f;
        }
      }
    }
  }
  std::vector<FusionView> cropped = whole;
  for (size_t v = 0; v < cropped.size(); ++v) {
    cropped[v].CropToDepth();
    EXPECT_EQ(cropped[v].col0, boxes[v].x0);
    EXPECT_EQ(cropped[v].row0, boxes[v].y0);
    EXPECT_EQ(cropped[v].depth.Width(), boxes[v].width);
    EXPECT_EQ(cropped[v].depth.Height(), boxes[v].height);
    EXPECT_EQ(cropped[v].Whole(cropped[v].depth).Data(), whole[v].depth.Data());
  }
  GeometricPrior whole_prior, cropped_prior;
  for (const FusionView& view : whole) whole_prior.views.push_back(&view);
  for (const FusionView& view : cropped) cropped_prior.views.push_back(&view);
  for (GeometricPrior* prior : {&whole_prior, &cropped_prior}) {
    prior->weight = 2.0;
    prior->max_error_px = 6.0;
  }
  const StereoCamera camera = CameraOf(ref);
  const DepthLabels labels(0.5, 2.0, 64, /*inverse=*/true);
  const size_t size = static_cast<size_t>(camera.width) * camera.height * labels.num_labels;
  std::vector<float> cpu_whole(size, 0.0f), cpu_cropped = cpu_whole, cl_whole = cpu_whole,
                     cl_cropped = cpu_whole;
  AddGeometricPriorCpu(whole_prior, camera, 1.0, labels, {}, 1.0f, labels.num_labels, {}, 0.5f,
                       &cpu_whole);
  AddGeometricPriorCpu(cropped_prior, camera, 1.0, labels, {}, 1.0f, labels.num_labels, {},
                       0.5f, &cpu_cropped);
  GeometricPriorCL(context.get(), whole_prior)
      .Add(camera, 1.0, labels, {}, 1.0f, labels.num_labels, {}, 0.5f, &cl_whole);
  GeometricPriorCL(context.get(), cropped_prior)
      .Add(camera, 1.0, labels, {}, 1.0f, labels.num_labels, {}, 0.5f, &cl_cropped);
  EXPECT_EQ(cpu_cropped, cpu_whole);
  EXPECT_EQ(cl_cropped, cl_whole);
  // The boxes cut what the views see: entries between no error and the maximum on both sides.
  size_t partial = 0;
  for (float cost : cpu_whole) partial += cost > 0.01f && cost < 0.99f;
  EXPECT_GT(partial, size / 20);
  // And the reference's points at its depths project on both sides of each box's edges: pixels
  // just inside and just outside are read.
  for (size_t v = 0; v < whole.size(); ++v) {
    int inside = 0, outside = 0;
    for (int row = 0; row < camera.height; ++row) {
      for (int col = 0; col < camera.width; ++col) {
        int c, r;
        double z;
        const Eigen::Vector3d world = CameraOf(ref).BackProject(col, row, ref.depth.At(row, col));
        if (!whole[v].Project(world, &c, &r, &z)) continue;
        const PixelBox& box = boxes[v];
        const int x1 = box.x0 + box.width, y1 = box.y0 + box.height;  // past the box
        const bool near_an_edge = std::min({std::abs(c - box.x0), std::abs(c - x1),
                                            std::abs(r - box.y0), std::abs(r - y1)}) <= 1;
        if (!near_an_edge) continue;
        (c >= box.x0 && r >= box.y0 && c < x1 && r < y1 ? inside : outside) += 1;
      }
    }
    EXPECT_GT(inside, 10) << v;
    EXPECT_GT(outside, 10) << v;
  }
}

}  // namespace
}  // namespace hairmvs
