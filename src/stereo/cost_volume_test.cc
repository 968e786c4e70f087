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

// A reference at a level of 48 x 36 (of a 96 x 72 camera) and two sources of other sizes, one
// rolled: random fields, so every sample position and the roll factor matter.
Scene MakeScene(int channels) {
  Scene scene;
  const StereoCamera ref = LookAtCamera({0, 0, 0}, {0, 0, 1}, 100, 96, 72);
  scene.ref = {ref, RandomMap(48, 36, channels, 1, channels == 3 ? 0.0f : -1.0f)};
  scene.sources.push_back({LookAtCamera({0.25, 0, 0}, {0, 0, 1}, 100, 96, 72, 0.7),
                           RandomMap(48, 36, channels, 2, channels == 3 ? 0.0f : -1.0f)});
  scene.sources.push_back({LookAtCamera({0, 0.2, 0.05}, {0, 0, 1}, 90, 80, 60),
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
  // Uniform-in-depth labels too.
  const DepthLabels linear(0.6, 2.0, 32, false);
  CostVolumeCL volume(context.get(), StereoCost::kOrientation, scene.ref, scene.sources,
                      OrientationTransfer::kPlaneHomography);
  EXPECT_LT(MaxAbsDiff(volume.Compute(scene.base, 1.0f, 0, 4, linear),
                       OrientationCostCpu(scene.ref, scene.sources, scene.base, 1.0f, 0, 4,
                                          linear, OrientationTransfer::kPlaneHomography)),
            2e-4f);
}

TEST(CostVolume, PhotometricKernelsMatchTheCpuReference) {
  auto context = OpenCLContext::Create();
  const Scene scene = MakeScene(3);
  const DepthLabels labels(0.6, 2.0, 32, true);
  CostVolumeCL volume(context.get(), StereoCost::kPhotometric, scene.ref, scene.sources,
                      OrientationTransfer::kNone, 2);
  const FloatMap got = volume.Compute(scene.base, 0.75f, 5, 3, labels);
  const FloatMap expected =
      PhotometricCostCpu(scene.ref, scene.sources, scene.base, 0.75f, 5, 3, labels, 2);
  EXPECT_LT(MaxAbsDiff(got, expected), 2e-3f);
}

TEST(CostVolume, ResampleAccumulateMatchesBilinearResampling) {
  auto context = OpenCLContext::Create();
  const FloatMap src = RandomMap(13, 9, 3, 4);
  const FloatMap expected = ResampleBilinear(src, 25, 18);
  ResampleAccumulateCL resample(context.get());
  std::vector<float> volume(25 * 18 * 5, 1.0f);
  cl::Buffer src_buffer(context->Context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                        sizeof(float) * src.Data().size(), const_cast<float*>(src.Data().data()));
  cl::Buffer volume_buffer(context->Context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR,
                           sizeof(float) * volume.size(), volume.data());
  resample.Run(src_buffer, 13, 9, 3, volume_buffer, 25, 18, 1, 2.0f);
  context->Queue().enqueueReadBuffer(volume_buffer, CL_TRUE, 0, sizeof(float) * volume.size(),
                                     volume.data());
  const size_t plane = 25 * 18;
  for (size_t i = 0; i < plane; ++i) {
    EXPECT_FLOAT_EQ(volume[i], 1.0f);
    EXPECT_FLOAT_EQ(volume[4 * plane + i], 1.0f);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(volume[(k + 1) * plane + i], 1.0f + 2.0f * expected.Data()[k * plane + i], 1e-5);
    }
  }
}

}  // namespace
}  // namespace hairmvs
