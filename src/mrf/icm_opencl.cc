#include "src/mrf/icm_opencl.h"

#include <algorithm>
#include <limits>
#include <string>

namespace hairmvs {

void RunIcmOpenCL(OpenCLContext* context, const cl::Buffer& cost, const cl::Buffer& offset,
                  const cl::Buffer& weight_right, const cl::Buffer& weight_down,
                  const MrfProblem& problem, int max_sweeps, const cl::Buffer& labels) {
  cl::CommandQueue& queue = context->Queue();
  cl::Program& program =
      context->Program({"mrf_icm.cl"}, "-D NUM_LABELS=" + std::to_string(problem.num_labels));
  cl::Kernel kernel(program, "icm_colour");
  cl::Buffer changed_buffer(context->Context(), CL_MEM_READ_WRITE, sizeof(int));
  const size_t n = problem.NumPixels();
  constexpr int kLocalSize = 16;  // fixed: PoCL specialises kernels per local size
  const cl::NDRange global((n + kLocalSize - 1) / kLocalSize * kLocalSize);
  kernel.setArg(0, cost);
  kernel.setArg(1, offset);
  kernel.setArg(2, problem.label_step);
  kernel.setArg(3, weight_right);
  kernel.setArg(4, weight_down);
  kernel.setArg(5, std::min(problem.truncation, std::numeric_limits<float>::max()));
  kernel.setArg(6, problem.width);
  kernel.setArg(7, problem.height);
  kernel.setArg(9, labels);
  kernel.setArg(10, changed_buffer);
  for (int sweep = 0; sweep < max_sweeps; ++sweep) {
    queue.enqueueFillBuffer(changed_buffer, 0, 0, sizeof(int));
    for (int colour = 0; colour < 2; ++colour) {
      kernel.setArg(8, colour);
      queue.enqueueNDRangeKernel(kernel, cl::NullRange, global, cl::NDRange(kLocalSize));
    }
    int changed = 0;
    queue.enqueueReadBuffer(changed_buffer, CL_TRUE, 0, sizeof(int), &changed);
    if (!changed) break;
  }
}

}  // namespace hairmvs
