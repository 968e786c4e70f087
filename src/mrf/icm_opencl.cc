#include "src/mrf/icm_opencl.h"

#include <algorithm>
#include <limits>
#include <string>

namespace hairmvs {

std::vector<int> MrfReadLabels(cl::CommandQueue& queue, const cl::Buffer& labels, size_t n) {
  std::vector<int> host(n);
  queue.enqueueReadBuffer(labels, CL_TRUE, 0, n * sizeof(int), host.data());
  return host;
}

void SetCheckerboardKernelArgs(cl::Kernel* kernel, const cl::Buffer& cost,
                               const cl::Buffer& offset, const cl::Buffer& weight_right,
                               const cl::Buffer& weight_down, const MrfProblem& problem) {
  kernel->setArg(0, cost);
  kernel->setArg(1, offset);
  kernel->setArg(2, problem.label_step);
  kernel->setArg(3, weight_right);
  kernel->setArg(4, weight_down);
  kernel->setArg(5, std::min(problem.truncation, std::numeric_limits<float>::max()));
  kernel->setArg(6, problem.width);
  kernel->setArg(7, problem.height);
}

void RunIcmOpenCL(OpenCLContext* context, const cl::Buffer& cost, const cl::Buffer& offset,
                  const cl::Buffer& weight_right, const cl::Buffer& weight_down,
                  const MrfProblem& problem, int max_sweeps, const cl::Buffer& labels) {
  cl::CommandQueue& queue = context->Queue();
  cl::Program& program =
      context->Program({"mrf_icm.cl"}, "-D NUM_LABELS=" + std::to_string(problem.num_labels));
  cl::Kernel kernel(program, "icm_colour");
  cl::Buffer changed_buffer = context->Buffer(CL_MEM_READ_WRITE, sizeof(int));
  const cl::NDRange global = MrfGlobalRange(problem.NumPixels());
  SetCheckerboardKernelArgs(&kernel, cost, offset, weight_right, weight_down, problem);
  kernel.setArg(9, labels);
  kernel.setArg(10, changed_buffer);
  for (int sweep = 0; sweep < max_sweeps; ++sweep) {
    queue.enqueueFillBuffer(changed_buffer, 0, 0, sizeof(int));
    for (int colour = 0; colour < 2; ++colour) {
      kernel.setArg(8, colour);
      queue.enqueueNDRangeKernel(kernel, cl::NullRange, global, cl::NDRange(kMrfLocalSize));
    }
    int changed = 0;
    queue.enqueueReadBuffer(changed_buffer, CL_TRUE, 0, sizeof(int), &changed);
    if (!changed) break;
  }
}

}  // namespace hairmvs
