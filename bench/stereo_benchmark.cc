// Throughput of the stereo kernels on PoCL: the orientation and photometric cost volumes and
// the guided filter for one block of depth slices at 960 x 640 (the gantry set's size), 3 source
// views; the geometric pass's prior for a fine band of 16 labels and 8 other views' maps.
// Run: ./build/bench/stereo_benchmark

#include <benchmark/benchmark.h>

#include <cmath>

#include "src/opencl/opencl_context.h"
#include "src/stereo/cost_volume.h"
#include "src/stereo/geometric_prior.h"
#include "src/stereo/guided_filter.h"
#include "src/stereo/stereo_test_util.h"

namespace hairmvs {
namespace {

using testing_util::LookAtCamera;
using testing_util::RandomMap;

constexpr int kWidth = 960, kHeight = 640, kSlices = 8;

// One block of kSlices slices of `cost` between random fields (2 channels in [-1, 1] for the
// orientation cost, 3 colour channels in [0, 1] for the photometric one) of a reference and
// three sources 0.1 m aside, 0.6 m from the scene.
void MeasureCostVolume(benchmark::State& state, StereoCost cost, OrientationTransfer transfer,
                       bool tilted_planes) {
  auto context = OpenCLContext::Create();
  const bool orientation = cost == StereoCost::kOrientation;
  const int channels = orientation ? 2 : 3;
  const float lo = orientation ? -1.0f : 0.0f;
  const CostViewInput ref(LookAtCamera({0, 0, 0}, {0, 0, 0.6}, 768, kWidth, kHeight),
                          RandomMap(kWidth, kHeight, channels, 1, lo, 1),
                          tilted_planes ? RandomMap(kWidth, kHeight, 2, 5, -1e-3f, 1e-3f)
                                        : FloatMap());
  std::vector<CostViewInput> sources;
  const Eigen::Vector3d centers[3] = {{0.1, 0, 0}, {-0.1, 0, 0}, {0, 0.1, 0}};
  for (int v = 0; v < 3; ++v) {
    sources.push_back({LookAtCamera(centers[v], {0, 0, 0.6}, 768, kWidth, kHeight),
                       RandomMap(kWidth, kHeight, channels, 2 + v, lo, 1)});
  }
  CostVolumeCL volume(context.get(), cost, ref, sources, transfer);
  const DepthLabels labels(0.4, 0.8, 64, true);
  std::vector<float> base(kWidth * kHeight, 0.0f);
  cl::Buffer base_buffer(context->Context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                         sizeof(float) * base.size(), base.data());
  cl::Buffer out(context->Context(), CL_MEM_READ_WRITE,
                 sizeof(float) * base.size() * kSlices);
  for (auto _ : state) {
    volume.Compute(base_buffer, 1.0f, 0, kSlices, labels, out);
    context->Queue().finish();
  }
  state.counters["Mpixel_slices/s"] = benchmark::Counter(
      1e-6 * kWidth * kHeight * kSlices, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_OrientationCostVolume(benchmark::State& state) {
  // Argument 0: the paper's epipole roll; 1: the plane homography through the fronto-parallel
  // plane; 2: through planes tilted per pixel (strand_plane_from_visual_hull, the default).
  MeasureCostVolume(state, StereoCost::kOrientation,
                    state.range(0) == 0 ? OrientationTransfer::kEpipoleRoll
                                        : OrientationTransfer::kPlaneHomography,
                    state.range(0) == 2);
}
BENCHMARK(BM_OrientationCostVolume)
    ->ArgName("roll_plane_tilted")
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond);

// The photometric baseline's cost (zero-mean NCC of 7 x 7 colour windows) for the same block.
void BM_PhotometricCostVolume(benchmark::State& state) {
  MeasureCostVolume(state, StereoCost::kPhotometric, OrientationTransfer::kPlaneHomography,
                    false);
}
BENCHMARK(BM_PhotometricCostVolume)->Unit(benchmark::kMillisecond);

void BM_GuidedFilter(benchmark::State& state) {
  auto context = OpenCLContext::Create();
  GuidedFilterCL filter(context.get(), RandomMap(kWidth, kHeight, 2, 7),
                        static_cast<int>(state.range(0)), 0.12f);
  const FloatMap input = RandomMap(kWidth, kHeight, kSlices, 8);
  cl::Buffer buffer(context->Context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR,
                    sizeof(float) * input.Data().size(), const_cast<float*>(input.Data().data()));
  for (auto _ : state) {
    filter.Filter(buffer, kSlices, buffer);
    context->Queue().finish();
  }
  state.counters["Mpixel_slices/s"] = benchmark::Counter(
      1e-6 * kWidth * kHeight * kSlices, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_GuidedFilter)->Arg(3)->Arg(7)->Unit(benchmark::kMillisecond);

// The geometric pass's prior (kernels/geometric_prior.cl) on the fine band: 16 labels half a
// label apart around a random base, every pixel, 8 other views 0.1 m apart whose maps hold a
// noisy plane 0.6 m away (the gantry's geometric pass reads 3 to 23 maps per view).
void BM_GeometricPrior(benchmark::State& state) {
  auto context = OpenCLContext::Create();
  const StereoCamera ref = LookAtCamera({0, 0, 0}, {0, 0, 0.6}, 768, kWidth, kHeight);
  std::vector<FusionView> views;
  for (int v = 0; v < 8; ++v) {
    const double angle = 2 * M_PI * v / 8;
    const StereoCamera camera = LookAtCamera(
        {0.1 * std::cos(angle), 0.1 * std::sin(angle), 0}, {0, 0, 0.6}, 768, kWidth, kHeight);
    FusionView view;
    view.K = camera.K;
    view.R = camera.R;
    view.t = camera.t;
    view.depth = RandomMap(kWidth, kHeight, 1, 10 + v, 0.59f, 0.61f);
    views.push_back(std::move(view));
  }
  GeometricPrior prior;
  for (const FusionView& view : views) prior.views.push_back(&view);
  prior.weight = 2;
  prior.max_error_px = 6;
  GeometricPriorCL prior_cl(context.get(), prior);
  const DepthLabels labels(0.4, 0.8, 128, true);
  const FloatMap base = RandomMap(kWidth, kHeight, 1, 9, 50, 60);
  constexpr int kBand = 16;
  std::vector<float> volume(static_cast<size_t>(kWidth) * kHeight * kBand, 0.0f);
  for (auto _ : state) {
    prior_cl.Add(ref, 1.0, labels, base.Data(), 0.5f, kBand, {}, 1.0f, &volume);
  }
  state.counters["Mpixel_labels/s"] = benchmark::Counter(
      1e-6 * kWidth * kHeight * kBand, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_GeometricPrior)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace hairmvs
BENCHMARK_MAIN();
