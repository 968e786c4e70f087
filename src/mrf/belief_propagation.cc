#include "src/mrf/belief_propagation.h"

#include <algorithm>
#include <limits>
#include <string>

#include "src/core/logging.h"
#include "src/mrf/icm_opencl.h"
#include "src/mrf/semi_global.h"
#include "src/opencl/opencl_context.h"

namespace hairmvs {

std::vector<int> SolveBeliefPropagationCpu(const MrfProblem& problem, int iterations) {
  const int width = problem.width;
  const int height = problem.height;
  const int num_labels = problem.num_labels;
  const size_t n = problem.NumPixels();
  const std::vector<float> zeros(n, 0.0f);
  const std::vector<float>& offset = problem.label_offset.empty() ? zeros : problem.label_offset;
  const std::vector<float>& weight_right =
      problem.weight_right.empty() ? zeros : problem.weight_right;
  const std::vector<float>& weight_down = problem.weight_down.empty() ? zeros : problem.weight_down;
  const float step = problem.label_step;
  const float truncation = std::min(problem.truncation, std::numeric_limits<float>::max());
  const float kInf = std::numeric_limits<float>::infinity();
  // [slot][label][pixel]: the message received from the left (0), right (1), upper (2) and
  // lower (3) neighbour.
  std::vector<float> msg(4 * n * num_labels, 0.0f);
  auto at = [&](int slot, int label, size_t p) -> float& {
    return msg[(static_cast<size_t>(slot) * num_labels + label) * n + p];
  };
  std::vector<float> h(num_labels), prev(num_labels), m(num_labels), z(num_labels + 1);
  std::vector<int> v(num_labels);
  for (int iteration = 0; iteration < iterations; ++iteration) {
    for (int colour = 0; colour < 2; ++colour) {
      for (int row = 0; row < height; ++row) {
        for (int col = (row + colour) & 1; col < width; col += 2) {
          const size_t p = static_cast<size_t>(row) * width + col;
          for (int a = 0; a < num_labels; ++a) {
            h[a] = problem.data_cost[a * n + p] + at(0, a, p) + at(1, a, p) + at(2, a, p) +
                   at(3, a, p);
          }
          for (int k = 0; k < 4; ++k) {
            size_t q;
            float w;
            if (k == 0) {
              if (col == 0) continue;
              q = p - 1;
              w = weight_right[p - 1];
            } else if (k == 1) {
              if (col + 1 == width) continue;
              q = p + 1;
              w = weight_right[p];
            } else if (k == 2) {
              if (row == 0) continue;
              q = p - width;
              w = weight_down[p - width];
            } else {
              if (row + 1 == height) continue;
              q = p + width;
              w = weight_down[p];
            }
            float prev_min = kInf;
            for (int a = 0; a < num_labels; ++a) {
              prev[a] = h[a] - at(k, a, p);
              prev_min = std::min(prev_min, prev[a]);
            }
            SemiGlobalPathMin(prev.data(), prev_min, num_labels, step, offset[q] - offset[p], w,
                              truncation, v.data(), z.data(), m.data());
            float m_min = kInf;
            for (int b = 0; b < num_labels; ++b) m_min = std::min(m_min, m[b]);
            for (int b = 0; b < num_labels; ++b) at(k ^ 1, b, q) = m[b] - m_min;
          }
        }
      }
    }
  }
  std::vector<int> labels(n, 0);
  for (size_t p = 0; p < n; ++p) {
    float best = kInf;
    for (int a = 0; a < num_labels; ++a) {
      const float belief =
          problem.data_cost[a * n + p] + at(0, a, p) + at(1, a, p) + at(2, a, p) + at(3, a, p);
      if (belief < best) {
        best = belief;
        labels[p] = a;
      }
    }
  }
  return labels;
}

std::vector<int> SolveBeliefPropagationOpenCL(const MrfProblem& problem, int iterations,
                                              int icm_iterations, OpenCLContext* context) {
  CHECK(context != nullptr);
  const int num_labels = problem.num_labels;
  const size_t n = problem.NumPixels();
  THROW_IF(4 * n * num_labels > static_cast<size_t>(std::numeric_limits<int>::max()),
           "belief_propagation: the messages (4 x " << n << " pixels x " << num_labels
                                                    << " labels) exceed 32-bit indexing");
  const std::vector<float> zeros(n, 0.0f);
  const std::vector<float>& offset = problem.label_offset.empty() ? zeros : problem.label_offset;
  const std::vector<float>& weight_right =
      problem.weight_right.empty() ? zeros : problem.weight_right;
  const std::vector<float>& weight_down = problem.weight_down.empty() ? zeros : problem.weight_down;

  cl::CommandQueue& queue = context->Queue();
  const std::string options = "-D NUM_LABELS=" + std::to_string(num_labels);
  cl::Program& program = context->Program({"mrf_bp.cl"}, options);
  cl::Kernel colour_kernel(program, "bp_colour");
  cl::Kernel labels_kernel(program, "bp_labels");
  cl::Buffer cost_buffer = ReadOnlyBuffer(context, problem.data_cost);
  cl::Buffer offset_buffer = ReadOnlyBuffer(context, offset);
  cl::Buffer right_buffer = ReadOnlyBuffer(context, weight_right);
  cl::Buffer down_buffer = ReadOnlyBuffer(context, weight_down);
  const size_t msg_bytes = 4 * n * num_labels * sizeof(float);
  cl::Buffer msg_buffer = context->Buffer(CL_MEM_READ_WRITE, msg_bytes);
  cl::Buffer label_buffer = context->Buffer(CL_MEM_READ_WRITE, n * sizeof(int));
  queue.enqueueFillBuffer(msg_buffer, 0.0f, 0, msg_bytes);

  const cl::NDRange global = MrfGlobalRange(n);
  SetCheckerboardKernelArgs(&colour_kernel, cost_buffer, offset_buffer, right_buffer,
                            down_buffer, problem);
  colour_kernel.setArg(9, msg_buffer);
  for (int iteration = 0; iteration < iterations; ++iteration) {
    for (int colour = 0; colour < 2; ++colour) {
      colour_kernel.setArg(8, colour);
      queue.enqueueNDRangeKernel(colour_kernel, cl::NullRange, global, cl::NDRange(kMrfLocalSize));
    }
  }
  labels_kernel.setArg(0, cost_buffer);
  labels_kernel.setArg(1, msg_buffer);
  labels_kernel.setArg(2, static_cast<int>(n));
  labels_kernel.setArg(3, label_buffer);
  queue.enqueueNDRangeKernel(labels_kernel, cl::NullRange, global, cl::NDRange(kMrfLocalSize));
  if (icm_iterations > 0) {
    RunIcmOpenCL(context, cost_buffer, offset_buffer, right_buffer, down_buffer, problem,
                 icm_iterations, label_buffer);
  }
  return MrfReadLabels(queue, label_buffer, n);
}

}  // namespace hairmvs
