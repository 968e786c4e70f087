#pragma once
// Checkerboard ICM (kernels/mrf_icm.cl) on labels already on the device, after an OpenCL
// solver. Equal to PolishWithIcm (src/mrf/mrf.h) on the CPU. Also the small host-side
// helpers the OpenCL MRF solvers share. Internal to hairmvs_mrf.

#include <cstddef>
#include <vector>

#include "src/mrf/mrf.h"
#include "src/opencl/opencl_context.h"

namespace hairmvs {

// Fixed work-group size of the MRF kernels: PoCL specialises kernels per local size.
constexpr int kMrfLocalSize = 16;

// `count` work items rounded up to a multiple of kMrfLocalSize.
inline cl::NDRange MrfGlobalRange(size_t count) {
  return cl::NDRange(RoundUpToMultiple(count, kMrfLocalSize));
}

// Blocks until the queue is done and returns the n labels of `labels`.
std::vector<int> MrfReadLabels(cl::CommandQueue& queue, const cl::Buffer& labels, size_t n);

// Sets arguments 0..7 shared by the checkerboard kernels bp_colour and icm_colour: cost,
// offset, step, weight_right, weight_down, truncation (the problem's, clamped to a finite
// float), width, height.
void SetCheckerboardKernelArgs(cl::Kernel* kernel, const cl::Buffer& cost,
                               const cl::Buffer& offset, const cl::Buffer& weight_right,
                               const cl::Buffer& weight_down, const MrfProblem& problem);

// cost: [label][row][col]; offset, weight_right, weight_down: H * W floats (zeros where the
// problem's vectors are empty); labels: H * W ints, updated in place. Stops after a sweep
// that changed no label, or after max_sweeps.
void RunIcmOpenCL(OpenCLContext* context, const cl::Buffer& cost, const cl::Buffer& offset,
                  const cl::Buffer& weight_right, const cl::Buffer& weight_down,
                  const MrfProblem& problem, int max_sweeps, const cl::Buffer& labels);

}  // namespace hairmvs
