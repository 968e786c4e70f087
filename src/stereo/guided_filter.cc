#include "src/stereo/guided_filter.h"

#include <algorithm>

#include "src/core/logging.h"
#include "src/opencl/opencl_context.h"

namespace hairmvs {

namespace {

cl::Program& GuidedFilterProgram(OpenCLContext* context) {
  return context->Program({"guided_filter.cl"});
}

// Work-group sizes: per pixel (the guided filter's pointwise kernels) and per row or group of
// columns (the box filter's passes). Fixed, so that PoCL vectorises whatever the image's size
// (RoundUpToMultiple); the kernels check their bounds.
constexpr size_t kPixelGroup = 64;
constexpr size_t kLineGroup = 16;

// `count` work-items (rounded up) by `planes`, in groups of `group` x 1.
void EnqueueLines(cl::CommandQueue& queue, const cl::Kernel& kernel, size_t count,
                  size_t planes, size_t group) {
  queue.enqueueNDRangeKernel(kernel, cl::NullRange,
                             cl::NDRange(RoundUpToMultiple(count, group), planes),
                             cl::NDRange(group, 1));
}

}  // namespace

BoxFilterCL::BoxFilterCL(OpenCLContext* context)
    : context_(context),
      rows_(GuidedFilterProgram(context), "box_rows"),
      cols_(GuidedFilterProgram(context), "box_cols") {}

void BoxFilterCL::Mean(const cl::Buffer& in, const cl::Buffer& scratch, const cl::Buffer& out,
                       int width, int height, int num_planes, int radius) {
  rows_.setArg(0, in);
  rows_.setArg(1, scratch);
  rows_.setArg(2, width);
  rows_.setArg(3, height);
  rows_.setArg(4, radius);
  EnqueueLines(context_->Queue(), rows_, height, num_planes, kLineGroup);
  cols_.setArg(0, scratch);
  cols_.setArg(1, out);
  cols_.setArg(2, width);
  cols_.setArg(3, height);
  cols_.setArg(4, radius);
  // box_cols: a work-item per 8 columns.
  EnqueueLines(context_->Queue(), cols_, DivideRoundingUp(width, 8), num_planes, kLineGroup);
}

GuidedFilterCL::GuidedFilterCL(OpenCLContext* context, const FloatMap& guide, int radius,
                               float eps)
    : context_(context), width_(guide.Width()), height_(guide.Height()), radius_(radius),
      box_(context),
      products_(GuidedFilterProgram(context), "gf_products"),
      coefficients_(GuidedFilterProgram(context), "gf_coefficients"),
      output_(GuidedFilterProgram(context), "gf_output") {
  CHECK_EQ(guide.Channels(), 2);
  CHECK_GE(radius, 0);
  const int n = width_ * height_;
  const size_t plane_bytes = sizeof(float) * n;
  guide_ = ReadOnlyBuffer(context, guide.Data());
  cl::Buffer planes = context->Buffer(CL_MEM_READ_WRITE, 3 * plane_bytes);
  cl::Buffer scratch = context->Buffer(CL_MEM_READ_WRITE, 3 * plane_bytes);
  stats_ = context->Buffer(CL_MEM_READ_WRITE, 3 * plane_bytes);
  cl::Kernel guide_planes(GuidedFilterProgram(context), "gf_guide_planes");
  guide_planes.setArg(0, guide_);
  guide_planes.setArg(1, planes);
  guide_planes.setArg(2, n);
  EnqueueLines(context->Queue(), guide_planes, n, 1, kPixelGroup);
  box_.Mean(planes, scratch, stats_, width_, height_, 3, radius_);
  cl::Kernel guide_stats(GuidedFilterProgram(context), "gf_guide_stats");
  guide_stats.setArg(0, stats_);
  guide_stats.setArg(1, n);
  guide_stats.setArg(2, eps);
  EnqueueLines(context->Queue(), guide_stats, n, 1, kPixelGroup);
}

void GuidedFilterCL::EnsureScratch(int num_slices) {
  if (num_slices <= scratch_slices_) return;
  const size_t bytes = sizeof(float) * 3 * static_cast<size_t>(width_) * height_ * num_slices;
  planes_ = context_->Buffer(CL_MEM_READ_WRITE, bytes);
  scratch_ = context_->Buffer(CL_MEM_READ_WRITE, bytes);
  scratch_slices_ = num_slices;
}

void GuidedFilterCL::Filter(const cl::Buffer& in, int num_slices, const cl::Buffer& out) {
  EnsureScratch(num_slices);
  const int n = width_ * height_;
  cl::CommandQueue& queue = context_->Queue();
  products_.setArg(0, in);
  products_.setArg(1, guide_);
  products_.setArg(2, planes_);
  products_.setArg(3, n);
  EnqueueLines(queue, products_, n, num_slices, kPixelGroup);
  box_.Mean(planes_, scratch_, planes_, width_, height_, 3 * num_slices, radius_);
  coefficients_.setArg(0, planes_);
  coefficients_.setArg(1, stats_);
  coefficients_.setArg(2, n);
  EnqueueLines(queue, coefficients_, n, num_slices, kPixelGroup);
  box_.Mean(planes_, scratch_, planes_, width_, height_, 3 * num_slices, radius_);
  output_.setArg(0, planes_);
  output_.setArg(1, guide_);
  output_.setArg(2, out);
  output_.setArg(3, n);
  EnqueueLines(queue, output_, n, num_slices, kPixelGroup);
}

FloatMap GuidedFilterCL::Filter(const FloatMap& input) {
  CHECK_EQ(input.Width(), width_);
  CHECK_EQ(input.Height(), height_);
  const size_t bytes = sizeof(float) * input.Data().size();
  cl::Buffer buffer = context_->Buffer(CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, bytes,
                    const_cast<float*>(input.Data().data()));
  Filter(buffer, input.Channels(), buffer);
  FloatMap output(width_, height_, input.Channels());
  context_->Queue().enqueueReadBuffer(buffer, CL_TRUE, 0, bytes, output.Data().data());
  return output;
}

FloatMap BoxMeanCpu(const FloatMap& input, int radius) {
  const int w = input.Width(), h = input.Height();
  FloatMap output(w, h, input.Channels());
  for (int c = 0; c < input.Channels(); ++c) {
    for (int row = 0; row < h; ++row) {
      for (int col = 0; col < w; ++col) {
        double sum = 0;
        int count = 0;
        for (int r = std::max(row - radius, 0); r <= std::min(row + radius, h - 1); ++r) {
          for (int q = std::max(col - radius, 0); q <= std::min(col + radius, w - 1); ++q) {
            sum += input.At(r, q, c);
            ++count;
          }
        }
        output.At(row, col, c) = static_cast<float>(sum / count);
      }
    }
  }
  return output;
}

FloatMap GuidedFilterCpu(const FloatMap& guide, const FloatMap& input, int radius, double eps) {
  const int w = input.Width(), h = input.Height();
  CHECK_EQ(guide.Width(), w);
  CHECK_EQ(guide.Height(), h);
  CHECK_EQ(guide.Channels(), 2);
  FloatMap output(w, h, input.Channels());
  for (int c = 0; c < input.Channels(); ++c) {
    // Per window k (centred at each pixel): a_k (2-vector) and b_k, from explicit sums.
    std::vector<double> a0(w * h), a1(w * h), b(w * h);
    for (int row = 0; row < h; ++row) {
      for (int col = 0; col < w; ++col) {
        double n = 0, m0 = 0, m1 = 0, mgg = 0, mc = 0, m0c = 0, m1c = 0;
        for (int r = std::max(row - radius, 0); r <= std::min(row + radius, h - 1); ++r) {
          for (int q = std::max(col - radius, 0); q <= std::min(col + radius, w - 1); ++q) {
            const double g0 = guide.At(r, q, 0), g1 = guide.At(r, q, 1);
            const double v = input.At(r, q, c);
            n += 1;
            m0 += g0;
            m1 += g1;
            mgg += g0 * g0 + g1 * g1;
            mc += v;
            m0c += g0 * v;
            m1c += g1 * v;
          }
        }
        m0 /= n, m1 /= n, mgg /= n, mc /= n, m0c /= n, m1c /= n;
        const double variance = mgg - m0 * m0 - m1 * m1;
        const int k = row * w + col;
        a0[k] = (m0c - m0 * mc) / (variance + eps);
        a1[k] = (m1c - m1 * mc) / (variance + eps);
        b[k] = mc - a0[k] * m0 - a1[k] * m1;
      }
    }
    // q_p = average over the windows containing p of a_k . O_p + b_k.
    for (int row = 0; row < h; ++row) {
      for (int col = 0; col < w; ++col) {
        double sum = 0;
        int count = 0;
        for (int r = std::max(row - radius, 0); r <= std::min(row + radius, h - 1); ++r) {
          for (int q = std::max(col - radius, 0); q <= std::min(col + radius, w - 1); ++q) {
            const int k = r * w + q;
            sum += a0[k] * guide.At(row, col, 0) + a1[k] * guide.At(row, col, 1) + b[k];
            ++count;
          }
        }
        output.At(row, col, c) = static_cast<float>(sum / count);
      }
    }
  }
  return output;
}

}  // namespace hairmvs
