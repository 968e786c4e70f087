#include "src/stereo/cost_volume.h"

#include <gtest/gtest.h>

#include "src/opencl/opencl_context.h"
#include "src/stereo/stereo_test_util.h"

namespace hairmvs {
namespace {

using testing_util::LookAtCamera;
using testing_util::RandomMap;

float MaxAbsDiff(const FloatMap& a, const FloatMap& b) {
  EXPECT_EQ(a.Data().size(), b.Data().size());
  float m = 0;
  for (size_t i = 0; i < a.Data().size(); ++i) m = std::max(m, std::abs(a.Data()[i] - b.Data()[i]));
  return m;
}

struct Scene {
  CostViewInput ref;
  std::vector<CostViewInput> sources;
  std::vector<float> base;
};

// A reference at level 1 (48 x 36) of a 96 x 72 camera and two sources of other sizes, one
// rolled: random fields, so every sample position and the roll factor matter.
Scene MakeScene(int channels) {
  Scene scene;
  const StereoCamera ref = LookAtCamera({0, 0, 0}, {0, 0, 1}, 100, 96, 72).PyramidLevel(1);
  scene.ref = {ref, RandomMap(48, 36, channels, 1, channels == 3 ? 0.0f : -1.0f)};
  scene.sources.push_back(
      {LookAtCamera({0.25, 0, 0}, {0, 0, 1}, 100, 96, 72, 0.7).PyramidLevel(1),
       RandomMap(48, 36, channels, 2, channels == 3 ? 0.0f : -1.0f)});
  scene.sources.push_back({LookAtCamera({0, 0.2, 0.05}, {0, 0, 1}, 90, 80, 60).PyramidLevel(1),
                           RandomMap(40, 30, channels, 3, channels == 3 ? 0.0f : -1.0f)});
  scene.base.resize(48 * 36);
  for (size_t i = 0; i < scene.base.size(); ++i) scene.base[i] = 0.37f * (i % 5);
  return scene;
}

TEST(CostVolume, OrientationKernelMatchesTheCpuReference) {
  auto context = OpenCLContext::Create();
  const Scene scene = MakeScene(2);
  const DepthLabels labels(0.6, 2.0, 32, true);
  for (OrientationTransfer transfer :
       {OrientationTransfer::kEpipoleRoll, OrientationTransfer::kNone,
        OrientationTransfer::kPlaneHomography}) {
    CostVolumeCL volume(context.get(), StereoCost::kOrientation, scene.ref, scene.sources,
                        transfer);
    const FloatMap got = volume.Compute(scene.base, 0.75f, 5, 7, labels);
    const FloatMap expected =
        OrientationCostCpu(scene.ref, scene.sources, scene.base, 0.75f, 5, 7, labels, transfer);
    EXPECT_LT(MaxAbsDiff(got, expected), 2e-4f) << ToString(transfer);
  }
  // The transfers differ on this scene (a rolled source and one above), so each is checked.
  const FloatMap roll = OrientationCostCpu(scene.ref, scene.sources, scene.base, 0.75f, 5, 7,
                                           labels, OrientationTransfer::kEpipoleRoll);
  const FloatMap plane = OrientationCostCpu(scene.ref, scene.sources, scene.base, 0.75f, 5, 7,
                                            labels, OrientationTransfer::kPlaneHomography);
  EXPECT_GT(MaxAbsDiff(roll, plane), 0.05f);
  // The strands' plane tilted per pixel (gradients of log depth up to 0.03 per level-1 pixel:
  // planes up to 56 degrees from the image plane at this focal length of 50 px).
  Scene tilted = scene;
  tilted.ref.log_depth_gradient = RandomMap(48, 36, 2, 4, -0.03f, 0.03f);
  CostVolumeCL tilted_volume(context.get(), StereoCost::kOrientation, tilted.ref,
                             tilted.sources, OrientationTransfer::kPlaneHomography);
  const FloatMap tilted_cpu = OrientationCostCpu(tilted.ref, tilted.sources, tilted.base, 0.75f,
                                                 5, 7, labels,
                                                 OrientationTransfer::kPlaneHomography);
  EXPECT_LT(MaxAbsDiff(tilted_volume.Compute(tilted.base, 0.75f, 5, 7, labels), tilted_cpu),
            2e-4f);
  // A block of more slices than a work-item takes (8 in kernels/cost_volume.cl): two whole
  // chunks and a part of one.
  EXPECT_LT(MaxAbsDiff(tilted_volume.Compute(tilted.base, 0.75f, 3, 19, labels),
                       OrientationCostCpu(tilted.ref, tilted.sources, tilted.base, 0.75f, 3, 19,
                                          labels, OrientationTransfer::kPlaneHomography)),
            2e-4f);
  EXPECT_GT(MaxAbsDiff(tilted_cpu, plane), 0.05f);
  // Sources weighted (level0_weight_angle_deg): each view's term scaled by its weight.
  Scene weighted = scene;
  weighted.sources[0].weight = 0.4f;
  weighted.sources[1].weight = 2.5f;
  CostVolumeCL weighted_volume(context.get(), StereoCost::kOrientation, weighted.ref,
                               weighted.sources, OrientationTransfer::kPlaneHomography);
  const FloatMap weighted_cpu = OrientationCostCpu(weighted.ref, weighted.sources, weighted.base,
                                                   0.75f, 5, 7, labels,
                                                   OrientationTransfer::kPlaneHomography);
  EXPECT_LT(MaxAbsDiff(weighted_volume.Compute(weighted.base, 0.75f, 5, 7, labels), weighted_cpu),
            2e-4f);
  EXPECT_GT(MaxAbsDiff(weighted_cpu, plane), 0.05f);
  // A source in the middle of the depth range, looking the same way: the labels' points nearer
  // than 1.3 m lie behind it. And reference pixels without a field (outside the hair), as
  // most are in real views.
  Scene behind = scene;
  behind.sources.push_back({LookAtCamera({0.3, 0, 1.3}, {0.3, 0, 2.3}, 100, 96, 72).PyramidLevel(1),
                            RandomMap(48, 36, 2, 5, -1.0f)});
  for (int row = 10; row < 20; ++row) {
    for (int col = 5; col < 25; ++col) {
      behind.ref.field.At(row, col, 0) = behind.ref.field.At(row, col, 1) = 0.0f;
    }
  }
  for (OrientationTransfer transfer :
       {OrientationTransfer::kEpipoleRoll, OrientationTransfer::kPlaneHomography}) {
    CostVolumeCL behind_volume(context.get(), StereoCost::kOrientation, behind.ref,
                               behind.sources, transfer);
    const FloatMap behind_cpu = OrientationCostCpu(behind.ref, behind.sources, behind.base, 0.75f,
                                                   0, 32, labels, transfer);
    EXPECT_LT(MaxAbsDiff(behind_volume.Compute(behind.base, 0.75f, 0, 32, labels), behind_cpu),
              2e-4f)
        << "a source with points behind it, " << ToString(transfer);
  }
  // Uniform-in-depth labels too.
  const DepthLabels linear(0.6, 2.0, 32, false);
  CostVolumeCL volume(context.get(), StereoCost::kOrientation, scene.ref, scene.sources,
                      OrientationTransfer::kPlaneHomography);
  EXPECT_LT(MaxAbsDiff(volume.Compute(scene.base, 1.0f, 0, 4, linear),
                       OrientationCostCpu(scene.ref, scene.sources, scene.base, 1.0f, 0, 4,
                                          linear, OrientationTransfer::kPlaneHomography)),
            2e-4f);
}

// A source that sees the reference pixel's strand end-on (its camera centre lies on the strand's
// line at one label's depth): the piece projects to a point there, has no direction, and the
// source adds no term at that label, in the kernel as in the CPU reference. Every number here is
// a short binary fraction, so the projections coincide exactly in float as in double.
TEST(CostVolume, AStrandSeenEndOnAddsNoTerm) {
  auto context = OpenCLContext::Create();
  StereoCamera ref;  // at the origin looking along +z; row 17's pixel centres lie at y = cy
  ref.K << 64, 0, 32, 0, 64, 17.5, 0, 0, 1;
  ref.width = 64;
  ref.height = 35;
  const double end_on_depth = 1.0;  // label 16 of the labels below
  StereoCamera end_on;              // at (2, 0, 1) looking along -x, on the line y = 0, z = 1
  end_on.K << 64, 0, 32, 0, 64, 18, 0, 0, 1;
  end_on.R << 0, 0, 1, 0, 1, 0, -1, 0, 0;
  end_on.t = -end_on.R * Eigen::Vector3d(2, 0, end_on_depth);
  end_on.width = 64;
  end_on.height = 36;
  const StereoCamera other = LookAtCamera({0.2, 0.1, 0}, {0, 0, 1}, 64, 64, 35);
  CostViewInput ref_input(ref, RandomMap(64, 35, 2, 11));
  const int row = 17, col = 40;
  ref_input.field.At(row, col, 0) = 0.8f;  // a strand along the image's x axis
  ref_input.field.At(row, col, 1) = 0.0f;
  const std::vector<CostViewInput> with_end_on = {CostViewInput(end_on, RandomMap(64, 36, 2, 12)),
                                                  CostViewInput(other, RandomMap(64, 35, 2, 13))};
  const std::vector<CostViewInput> without_end_on = {with_end_on[1]};
  const DepthLabels labels(0.5, 1.5, 33, false);
  ASSERT_EQ(labels.Depth(16), end_on_depth);
  const std::vector<float> base(64 * 35, 0.0f);
  const auto cpu = [&](const std::vector<CostViewInput>& sources) {
    return OrientationCostCpu(ref_input, sources, base, 1.0f, 12, 8, labels,
                              OrientationTransfer::kPlaneHomography);
  };
  const FloatMap expected = cpu(with_end_on);
  const FloatMap expected_without = cpu(without_end_on);
  CostVolumeCL volume(context.get(), StereoCost::kOrientation, ref_input, with_end_on,
                      OrientationTransfer::kPlaneHomography);
  const FloatMap got = volume.Compute(base, 1.0f, 12, 8, labels);
  EXPECT_LT(MaxAbsDiff(got, expected), 2e-4f);
  // Slice 4 is label 16: the end-on source adds nothing there, and something at the labels
  // beside it, where the piece has a direction.
  EXPECT_EQ(expected.At(row, col, 4), expected_without.At(row, col, 4));
  EXPECT_NEAR(got.At(row, col, 4), expected_without.At(row, col, 4), 2e-4f);
  for (int k : {3, 5}) {
    EXPECT_GT(std::abs(expected.At(row, col, k) - expected_without.At(row, col, k)), 1e-3f)
        << "slice " << k;
  }
}

TEST(CostVolume, PhotometricKernelsMatchTheCpuReference) {
  auto context = OpenCLContext::Create();
  const Scene scene = MakeScene(3);
  const DepthLabels labels(0.6, 2.0, 32, true);
  // Window radii 1-3 (3 x 3 to the default 7 x 7), and a second, larger block of slices on the
  // same volume (its warp buffers grow).
  for (int radius : {1, 2, 3}) {
    CostVolumeCL volume(context.get(), StereoCost::kPhotometric, scene.ref, scene.sources,
                        OrientationTransfer::kNone, radius);
    EXPECT_LT(MaxAbsDiff(volume.Compute(scene.base, 0.75f, 5, 3, labels),
                         PhotometricCostCpu(scene.ref, scene.sources, scene.base, 0.75f, 5, 3,
                                            labels, radius)),
              2e-3f)
        << "radius " << radius;
    EXPECT_LT(MaxAbsDiff(volume.Compute(scene.base, 0.75f, 2, 11, labels),
                         PhotometricCostCpu(scene.ref, scene.sources, scene.base, 0.75f, 2, 11,
                                            labels, radius)),
              2e-3f)
        << "radius " << radius << ", 11 slices";
  }
  // Uniform-in-depth labels; a source with the labels' points nearer than 1.3 m behind it (as
  // in the orientation test); and flat colour in the reference and a source, whose windows
  // have no variance (their NCC counts 0).
  const DepthLabels linear(0.6, 2.0, 32, false);
  Scene odd = scene;
  odd.sources.push_back({LookAtCamera({0.3, 0, 1.3}, {0.3, 0, 2.3}, 100, 96, 72).PyramidLevel(1),
                         RandomMap(48, 36, 3, 5, 0.0f)});
  for (int row = 8; row < 24; ++row) {
    for (int col = 6; col < 30; ++col) {
      for (int c = 0; c < 3; ++c) {
        odd.ref.field.At(row, col, c) = 0.5f;
        odd.sources[0].field.At(row, col, c) = 0.25f;
      }
    }
  }
  for (const DepthLabels& sampling : {labels, linear}) {
    CostVolumeCL volume(context.get(), StereoCost::kPhotometric, odd.ref, odd.sources,
                        OrientationTransfer::kNone, 3);
    const FloatMap expected =
        PhotometricCostCpu(odd.ref, odd.sources, odd.base, 0.75f, 0, 32, sampling, 3);
    EXPECT_LT(MaxAbsDiff(volume.Compute(odd.base, 0.75f, 0, 32, sampling), expected), 2e-3f)
        << (sampling.inverse ? "inverse depth" : "depth");
  }
  // The NCC does not depend on the colours' level: every view 100 times darker (dark hair,
  // whose texture has a small variance) gives the same costs.
  Scene dark = scene;
  for (CostViewInput* view : {&dark.ref, &dark.sources[0], &dark.sources[1]}) {
    for (float& c : view->field.Data()) c *= 0.01f;
  }
  CostVolumeCL bright_volume(context.get(), StereoCost::kPhotometric, scene.ref, scene.sources,
                             OrientationTransfer::kNone, 3);
  CostVolumeCL dark_volume(context.get(), StereoCost::kPhotometric, dark.ref, dark.sources,
                           OrientationTransfer::kNone, 3);
  EXPECT_LT(MaxAbsDiff(dark_volume.Compute(dark.base, 0.75f, 5, 3, labels),
                       bright_volume.Compute(scene.base, 0.75f, 5, 3, labels)),
            2e-3f);
}

// Between pyramid levels: level 1 (13 x 9) up to level 0 (25 x 18), an output pixel half a
// source pixel wide, and level 0 down to level 2 (7 x 5), four source pixels wide.
TEST(CostVolume, ResampleAccumulateMatchesBilinearResampling) {
  auto context = OpenCLContext::Create();
  ResampleAccumulateCL resample(context.get());
  struct Case {
    int src_width, src_height, width, height;
    float src_pixels_per_pixel;
  };
  for (const Case& c : {Case{13, 9, 25, 18, 0.5f}, Case{25, 18, 7, 5, 4.0f}}) {
    const FloatMap src = RandomMap(c.src_width, c.src_height, 3, 4);
    const FloatMap expected = ResampleBilinear(src, c.width, c.height, c.src_pixels_per_pixel);
    const size_t plane = static_cast<size_t>(c.width) * c.height;
    std::vector<float> volume(plane * 5, 1.0f);
    cl::Buffer src_buffer(context->Context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                          sizeof(float) * src.Data().size(),
                          const_cast<float*>(src.Data().data()));
    cl::Buffer volume_buffer(context->Context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR,
                             sizeof(float) * volume.size(), volume.data());
    resample.Run(src_buffer, c.src_width, c.src_height, 3, volume_buffer, c.width, c.height, 1,
                 2.0f, c.src_pixels_per_pixel);
    context->Queue().enqueueReadBuffer(volume_buffer, CL_TRUE, 0, sizeof(float) * volume.size(),
                                       volume.data());
    for (size_t i = 0; i < plane; ++i) {
      EXPECT_FLOAT_EQ(volume[i], 1.0f);
      EXPECT_FLOAT_EQ(volume[4 * plane + i], 1.0f);
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(volume[(k + 1) * plane + i], 1.0f + 2.0f * expected.Data()[k * plane + i],
                    1e-5);
      }
    }
  }
}

// The CPU twin on a ramp: level 1's pixel i holds i; level 0's pixel c lies at level-1
// coordinate (c + 0.5) / 2 - 0.5 (clamped), whatever the sizes' ratio (13 is not 25 / 2).
TEST(CostVolume, ResampleBilinearFollowsThePyramidsGrid) {
  FloatMap ramp(13, 1, 1);
  for (int i = 0; i < 13; ++i) ramp.At(0, i, 0) = static_cast<float>(i);
  const FloatMap up = ResampleBilinear(ramp, 25, 1, 0.5);
  EXPECT_FLOAT_EQ(up.At(0, 0, 0), 0.0f);   // -0.25, clamped
  EXPECT_FLOAT_EQ(up.At(0, 3, 0), 1.25f);
  EXPECT_FLOAT_EQ(up.At(0, 24, 0), 11.75f);
}

}  // namespace
}  // namespace hairmvs

namespace hairmvs {
namespace {

// best_source_fraction's selection against the plain reference: 5 sources' volumes of values
// on a coarse grid (so that ties occur), each term's k lowest of its sources summed and scaled,
// added to what `out` holds.
TEST(SumBestSources, KernelMatchesTheCpuReference) {
  auto context = OpenCLContext::Create();
  const size_t size = 3000;
  const int num_volumes = 5;
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> level(-8, 8);
  std::vector<float> volumes(size * num_volumes);
  for (float& v : volumes) v = 0.25f * level(rng);
  const std::vector<float> start(size, 0.5f);
  cl::Buffer volumes_buffer(context->Context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                            sizeof(float) * volumes.size(), volumes.data());
  SumBestSourcesCL select(context.get());
  // Two terms, as the combined cost has: volumes 0-2 and 3-4.
  for (int num_best : {1, 2, 3}) {
    std::vector<float> expected = start, got(size);
    SumBestSourcesCpu(volumes, 0, 3, num_best, size, &expected);
    SumBestSourcesCpu(volumes, 3, 2, std::min(num_best, 2), size, &expected);
    cl::Buffer out(context->Context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR,
                   sizeof(float) * size, const_cast<float*>(start.data()));
    select.Run(volumes_buffer, 0, 3, num_best, size, out);
    select.Run(volumes_buffer, 3, 2, std::min(num_best, 2), size, out);
    context->Queue().enqueueReadBuffer(out, CL_TRUE, 0, sizeof(float) * size, got.data());
    for (size_t i = 0; i < size; ++i) {
      ASSERT_NEAR(got[i], expected[i], 1e-5f) << "element " << i << ", best " << num_best;
    }
  }
  // The reference itself on one element: 3 sources at 1, -2, -2 with the best 2: (-2 - 2) x 3/2.
  std::vector<float> one = {1.0f, -2.0f, -2.0f}, sum = {0.0f};
  SumBestSourcesCpu(one, 0, 3, 2, 1, &sum);
  EXPECT_FLOAT_EQ(sum[0], -6.0f);
}

}  // namespace
}  // namespace hairmvs
