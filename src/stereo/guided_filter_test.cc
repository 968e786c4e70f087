#include "src/stereo/guided_filter.h"

#include <gtest/gtest.h>

#include "src/opencl/opencl_context.h"
#include "src/stereo/stereo_test_util.h"

namespace hairmvs {
namespace {

using testing_util::RandomMap;

float MaxAbsDiff(const FloatMap& a, const FloatMap& b) {
  EXPECT_EQ(a.Data().size(), b.Data().size());
  float m = 0;
  for (size_t i = 0; i < a.Data().size(); ++i) m = std::max(m, std::abs(a.Data()[i] - b.Data()[i]));
  return m;
}

TEST(GuidedFilter, BoxMeansMatchTheCpuReference) {
  auto context = OpenCLContext::Create();
  BoxFilterCL box(context.get());
  // 30 and 50: windows past the image's height (23) and width (37), which the kernels clamp.
  for (int radius : {0, 1, 3, 7, 20, 30, 50}) {
    const FloatMap input = RandomMap(37, 23, 3, 7 + radius);
    const size_t bytes = sizeof(float) * input.Data().size();
    cl::Buffer in(context->Context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, bytes,
                  const_cast<float*>(input.Data().data()));
    cl::Buffer scratch(context->Context(), CL_MEM_READ_WRITE, bytes);
    box.Mean(in, scratch, in, 37, 23, 3, radius);  // in place
    FloatMap got(37, 23, 3);
    context->Queue().enqueueReadBuffer(in, CL_TRUE, 0, bytes, got.Data().data());
    EXPECT_LT(MaxAbsDiff(got, BoxMeanCpu(input, radius)), 1e-5f) << "radius " << radius;
  }
}

TEST(GuidedFilter, MatchesTheWindowByWindowCpuReference) {
  auto context = OpenCLContext::Create();
  for (int radius : {1, 3, 5, 7}) {
    const FloatMap guide = RandomMap(41, 29, 2, 3 * radius);
    const FloatMap input = RandomMap(41, 29, 4, 5 * radius + 1, -3, 1);
    GuidedFilterCL filter(context.get(), guide, radius, 0.12f);
    const FloatMap got = filter.Filter(input);
    EXPECT_LT(MaxAbsDiff(got, GuidedFilterCpu(guide, input, radius, 0.12)), 2e-4f)
        << "radius " << radius;
  }
}

TEST(GuidedFilter, PreservesConstantsAndFollowsTheGuide) {
  auto context = OpenCLContext::Create();
  // Constant input stays constant (the weights of Eq. 8 sum to 1).
  const FloatMap guide = RandomMap(30, 20, 2, 11);
  GuidedFilterCL filter(context.get(), guide, 3, 0.12f);
  const FloatMap constant(30, 20, 1, 2.5f);
  EXPECT_LT(MaxAbsDiff(filter.Filter(constant), constant), 1e-4f);
  // Two regions of different orientation: cost edges aligned with the guide's edge survive
  // better than under a plain box filter.
  FloatMap split_guide(30, 20, 2), step(30, 20, 1);
  for (int row = 0; row < 20; ++row) {
    for (int col = 0; col < 30; ++col) {
      const bool left = col < 15;
      split_guide.At(row, col, 0) = left ? 1.0f : -1.0f;
      step.At(row, col) = left ? 0.0f : 1.0f;
    }
  }
  GuidedFilterCL edge_filter(context.get(), split_guide, 3, 0.12f);
  const FloatMap filtered = edge_filter.Filter(step);
  const FloatMap boxed = BoxMeanCpu(step, 3);
  EXPECT_LT(std::abs(filtered.At(10, 14) - 0.0f), std::abs(boxed.At(10, 14) - 0.0f));
  EXPECT_LT(std::abs(filtered.At(10, 15) - 1.0f), std::abs(boxed.At(10, 15) - 1.0f));
}

}  // namespace
}  // namespace hairmvs
