#pragma once
// Checkerboard ICM (kernels/mrf_icm.cl) on labels already on the device, after an OpenCL
// solver. Equal to PolishWithIcm (src/mrf/mrf.h) on the CPU. Internal to hairmvs_mrf.

#include "src/mrf/mrf.h"
#include "src/opencl/opencl_context.h"

namespace hairmvs {

// cost: [label][row][col]; offset, weight_right, weight_down: H * W floats (zeros where the
// problem's vectors are empty); labels: H * W ints, updated in place. Stops after a sweep
// that changed no label, or after max_sweeps.
void RunIcmOpenCL(OpenCLContext* context, const cl::Buffer& cost, const cl::Buffer& offset,
                  const cl::Buffer& weight_right, const cl::Buffer& weight_down,
                  const MrfProblem& problem, int max_sweeps, const cl::Buffer& labels);

}  // namespace hairmvs
