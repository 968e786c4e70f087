#include "src/mrf/semi_global.h"

#include <algorithm>
#include <limits>
#include <string>

#include "src/core/logging.h"
#include "src/mrf/icm_opencl.h"
#include "src/opencl/opencl_context.h"

namespace hairmvs {
namespace {

// Infinite truncation is passed as FLT_MAX so that the kernel needs no special case (and does
// not depend on how a device treats infinities under its math options).
float FiniteTruncation(const MrfProblem& problem) {
  return std::min(problem.truncation, std::numeric_limits<float>::max());
}

int NumPaths(int width, int height, int dx, int dy) {
  if (dy == 0) return height;
  if (dx == 0) return width;
  return width + height - 1;
}

const std::vector<float>& DirectionWeights(const SemiGlobalEdgeWeights& weights, int dx, int dy) {
  if (dy == 0) return weights.right;
  if (dx == 0) return weights.down;
  return dx == dy ? weights.diag : weights.anti;
}

}  // namespace

void SemiGlobalPathMin(const float* prev, float prev_min, int num_labels, float step, float delta,
                       float weight, float truncation, int* v, float* z, float* m) {
  // The same float arithmetic, in the same order, as mrf_path_min in kernels/mrf_path_min.clh.
  const float kInf = std::numeric_limits<float>::infinity();
  if (!(weight > 0.0f)) {
    for (int b = 0; b < num_labels; ++b) m[b] = prev_min;
    return;
  }
  // Lower envelope of f_a(y) = prev[a] + weight * (y - a * step)^2: v[0..k] are the parabolas
  // on it, z[i] where parabola v[i] starts being the lowest.
  int k = 0;
  v[0] = 0;
  z[0] = -kInf;
  z[1] = kInf;
  for (int a = 1; a < num_labels; ++a) {
    const float xa = static_cast<float>(a) * step;
    const float ha = prev[a] + weight * (xa * xa);
    for (;;) {
      const float xc = static_cast<float>(v[k]) * step;
      const float hc = prev[v[k]] + weight * (xc * xc);
      const float s = (ha - hc) / (2.0f * weight * (xa - xc));
      if (k > 0 && s <= z[k]) {
        --k;
        continue;
      }
      ++k;
      v[k] = a;
      z[k] = s;
      z[k + 1] = kInf;
      break;
    }
  }
  const float truncated = prev_min + weight * truncation;
  k = 0;
  for (int b = 0; b < num_labels; ++b) {
    const float y = delta + static_cast<float>(b) * step;
    while (z[k + 1] < y) ++k;
    const float d = y - static_cast<float>(v[k]) * step;
    m[b] = std::min(prev[v[k]] + weight * (d * d), truncated);
  }
}

std::vector<std::array<int, 2>> SemiGlobalDirections(int num_directions) {
  CHECK(num_directions == 4 || num_directions == 8) << num_directions;
  std::vector<std::array<int, 2>> dirs = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  if (num_directions == 8) {
    dirs.insert(dirs.end(), {{1, 1}, {-1, -1}, {-1, 1}, {1, -1}});
  }
  return dirs;
}

SemiGlobalEdgeWeights ComputeSemiGlobalEdgeWeights(const MrfProblem& problem) {
  const int w = problem.width;
  const int h = problem.height;
  const size_t n = problem.NumPixels();
  SemiGlobalEdgeWeights out;
  out.right = problem.weight_right.empty() ? std::vector<float>(n, 0.0f) : problem.weight_right;
  out.down = problem.weight_down.empty() ? std::vector<float>(n, 0.0f) : problem.weight_down;
  out.diag.assign(n, 0.0f);
  out.anti.assign(n, 0.0f);
  auto R = [&](int c, int r) { return out.right[static_cast<size_t>(r) * w + c]; };
  auto D = [&](int c, int r) { return out.down[static_cast<size_t>(r) * w + c]; };
  for (int r = 0; r + 1 < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const size_t e = static_cast<size_t>(r) * w + c;
      if (c + 1 < w) {
        // (c,r) -> (c+1,r+1): via (c+1,r) or via (c,r+1).
        out.diag[e] = 0.5f * (std::min(R(c, r), D(c + 1, r)) + std::min(D(c, r), R(c, r + 1)));
      }
      if (c > 0) {
        // (c,r) -> (c-1,r+1): via (c-1,r) or via (c,r+1).
        out.anti[e] =
            0.5f * (std::min(R(c - 1, r), D(c - 1, r)) + std::min(D(c, r), R(c - 1, r + 1)));
      }
    }
  }
  return out;
}

std::vector<int> SolveSemiGlobalCpu(const MrfProblem& problem, int num_directions) {
  const int width = problem.width;
  const int height = problem.height;
  const int num_labels = problem.num_labels;
  const size_t n = problem.NumPixels();
  const std::vector<float> offset =
      problem.label_offset.empty() ? std::vector<float>(n, 0.0f) : problem.label_offset;
  const float step = problem.label_step;
  const float truncation = FiniteTruncation(problem);
  const SemiGlobalEdgeWeights weights = ComputeSemiGlobalEdgeWeights(problem);
  const float* cost = problem.data_cost.data();
  std::vector<float> sum(n * num_labels, 0.0f);
  std::vector<float> prev(num_labels);
  std::vector<float> cur(num_labels);
  std::vector<float> m(num_labels);
  std::vector<float> z(num_labels + 1);
  std::vector<int> v(num_labels);
  const float kInf = std::numeric_limits<float>::infinity();

  for (const auto& dir : SemiGlobalDirections(num_directions)) {
    const int dx = dir[0];
    const int dy = dir[1];
    const std::vector<float>& weight = DirectionWeights(weights, dx, dy);
    const bool upper_is_prev = dy > 0 || (dy == 0 && dx > 0);
    const int num_paths = NumPaths(width, height, dx, dy);
    for (int k = 0; k < num_paths; ++k) {
      // The path's first pixel: the same enumeration as sgm_path in kernels/mrf_sgm.cl.
      int col;
      int row;
      if (dy == 0) {
        row = k;
        col = dx > 0 ? 0 : width - 1;
      } else if (dx == 0) {
        col = k;
        row = dy > 0 ? 0 : height - 1;
      } else if (k < width) {
        col = k;
        row = dy > 0 ? 0 : height - 1;
      } else {
        const int j = k - width + 1;
        col = dx > 0 ? 0 : width - 1;
        row = dy > 0 ? j : height - 1 - j;
      }
      size_t p = static_cast<size_t>(row) * width + col;
      float prev_min = kInf;
      for (int b = 0; b < num_labels; ++b) {
        prev[b] = cost[b * n + p];
        prev_min = std::min(prev_min, prev[b]);
        sum[b * n + p] += prev[b];
      }
      float prev_offset = offset[p];
      for (;;) {
        col += dx;
        row += dy;
        if (col < 0 || col >= width || row < 0 || row >= height) break;
        const size_t q = p;
        p = static_cast<size_t>(row) * width + col;
        const float w = weight[upper_is_prev ? q : p];
        const float cur_offset = offset[p];
        SemiGlobalPathMin(prev.data(), prev_min, num_labels, step, cur_offset - prev_offset, w,
                          truncation, v.data(), z.data(), m.data());
        float cur_min = kInf;
        for (int b = 0; b < num_labels; ++b) {
          cur[b] = cost[b * n + p] + (m[b] - prev_min);
          cur_min = std::min(cur_min, cur[b]);
        }
        for (int b = 0; b < num_labels; ++b) {
          prev[b] = cur[b];
          sum[b * n + p] += cur[b];
        }
        prev_min = cur_min;
        prev_offset = cur_offset;
      }
    }
  }

  std::vector<int> labels(n, 0);
  for (size_t p = 0; p < n; ++p) {
    float best = sum[p];
    for (int b = 1; b < num_labels; ++b) {
      if (sum[b * n + p] < best) {
        best = sum[b * n + p];
        labels[p] = b;
      }
    }
  }
  return labels;
}

std::vector<int> SolveSemiGlobalOpenCL(const MrfProblem& problem, int num_directions,
                                       int icm_iterations, OpenCLContext* context) {
  CHECK(context != nullptr);
  const int width = problem.width;
  const int height = problem.height;
  const int num_labels = problem.num_labels;
  const size_t n = problem.NumPixels();
  THROW_IF(n * num_labels > static_cast<size_t>(std::numeric_limits<int>::max()),
           "semi_global: the cost volume (" << n << " pixels x " << num_labels
                                            << " labels) exceeds the kernel's 32-bit indexing");
  const std::vector<float> offset =
      problem.label_offset.empty() ? std::vector<float>(n, 0.0f) : problem.label_offset;
  const SemiGlobalEdgeWeights weights = ComputeSemiGlobalEdgeWeights(problem);

  cl::CommandQueue& queue = context->Queue();
  cl::Program& program =
      context->Program({"mrf_sgm.cl"}, "-D NUM_LABELS=" + std::to_string(num_labels));
  cl::Buffer offset_buffer = ReadOnlyBuffer(context, offset);
  cl::Buffer label_buffer = context->Buffer(CL_MEM_READ_WRITE, n * sizeof(int));
  // Each direction's weight buffer stays alive until the queue has finished with it; [0] and
  // [2], directions (1, 0) and (0, 1), are weights.right and .down, which ICM reads too.
  std::vector<cl::Buffer> weight_buffers;
  {
    // The paths read and write all labels of a pixel at once: the costs and sums are
    // pixel-major on the device, the costs written transposed straight into the mapped buffer
    // (no second host copy of the volume).
    const size_t volume_bytes = n * num_labels * sizeof(float);
    cl::Buffer cost_buffer =
        context->Buffer(CL_MEM_READ_ONLY | CL_MEM_ALLOC_HOST_PTR, volume_bytes);
    float* cost_by_pixel = static_cast<float*>(queue.enqueueMapBuffer(
        cost_buffer, CL_TRUE, CL_MAP_WRITE_INVALIDATE_REGION, 0, volume_bytes));
    for (int b = 0; b < num_labels; ++b) {
      const float* slice = problem.data_cost.data() + b * n;
      for (size_t p = 0; p < n; ++p) cost_by_pixel[p * num_labels + b] = slice[p];
    }
    queue.enqueueUnmapMemObject(cost_buffer, cost_by_pixel);
    cl::Buffer sum_buffer = context->Buffer(CL_MEM_READ_WRITE, volume_bytes);
    queue.enqueueFillBuffer(sum_buffer, 0.0f, 0, volume_bytes);
    cl::Kernel path_kernel(program, "sgm_path");
    cl::Kernel argmin_kernel(program, "sgm_argmin");
    for (const auto& dir : SemiGlobalDirections(num_directions)) {
      const int dx = dir[0];
      const int dy = dir[1];
      weight_buffers.push_back(ReadOnlyBuffer(context, DirectionWeights(weights, dx, dy)));
      const int num_paths = NumPaths(width, height, dx, dy);
      path_kernel.setArg(0, cost_buffer);
      path_kernel.setArg(1, offset_buffer);
      path_kernel.setArg(2, problem.label_step);
      path_kernel.setArg(3, weight_buffers.back());
      path_kernel.setArg(4, FiniteTruncation(problem));
      path_kernel.setArg(5, width);
      path_kernel.setArg(6, height);
      path_kernel.setArg(7, dx);
      path_kernel.setArg(8, dy);
      path_kernel.setArg(9, num_paths);
      path_kernel.setArg(10, sum_buffer);
      queue.enqueueNDRangeKernel(path_kernel, cl::NullRange, MrfGlobalRange(num_paths),
                                 cl::NDRange(kMrfLocalSize));
    }
    argmin_kernel.setArg(0, sum_buffer);
    argmin_kernel.setArg(1, static_cast<int>(n));
    argmin_kernel.setArg(2, label_buffer);
    queue.enqueueNDRangeKernel(argmin_kernel, cl::NullRange, MrfGlobalRange(n),
                               cl::NDRange(kMrfLocalSize));
    // Done with the pixel-major volumes before ICM uploads its label-major one.
    queue.finish();
  }

  if (icm_iterations > 0) {
    const cl::Buffer label_major_cost = ReadOnlyBuffer(context, problem.data_cost);
    RunIcmOpenCL(context, label_major_cost, offset_buffer, weight_buffers[0], weight_buffers[2],
                 problem, icm_iterations, label_buffer);
  }
  return MrfReadLabels(queue, label_buffer, n);
}

}  // namespace hairmvs
