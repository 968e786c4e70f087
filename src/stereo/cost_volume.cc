#include "src/stereo/cost_volume.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <string>

#include "src/core/logging.h"
#include "src/opencl/opencl_context.h"

namespace hairmvs {

namespace {

// Slices per work-item of orientation_cost (SLICE_CHUNK in kernels/cost_volume.cl).
constexpr int kOrientationSliceChunk = 8;

cl::Program& CostProgram(OpenCLContext* context) {
  return context->Program({"cost_volume.cl"},
                          "-D SLICE_CHUNK=" + std::to_string(kOrientationSliceChunk));
}

// Bilinear sample with pixel centres at integers; false outside [0, w-1] x [0, h-1].
bool SampleBilinear(const FloatMap& map, int channel, double x, double y, double* value) {
  const int w = map.Width(), h = map.Height();
  if (!(x >= 0 && y >= 0 && x <= w - 1 && y <= h - 1)) return false;
  const int x0 = std::min(static_cast<int>(x), std::max(w - 2, 0));
  const int y0 = std::min(static_cast<int>(y), std::max(h - 2, 0));
  const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
  const double fx = x - x0, fy = y - y0;
  *value = (1 - fx) * (1 - fy) * map.At(y0, x0, channel) + fx * (1 - fy) * map.At(y0, x1, channel) +
           (1 - fx) * fy * map.At(y1, x0, channel) + fx * fy * map.At(y1, x1, channel);
  return true;
}

// Where the reference image point (x_ref, y_ref) of the ref field's grid (SfM: pixel (col, row)
// is (col + 0.5, row + 0.5)) at depth D lands in the source field's grid (pixel-centre
// coordinates: pixel centres at integers), through the world frame. False behind the camera.
bool ProjectCpu(const CostViewInput& ref, const CostViewInput& src, double x_ref, double y_ref,
                double depth, double* x, double* y) {
  const StereoCamera& r = ref.camera;
  const StereoCamera& s = src.camera;
  const Eigen::Vector3d ray = r.K.inverse() * Eigen::Vector3d(x_ref, y_ref, 1.0);
  const Eigen::Vector3d world = r.R.transpose() * (depth * ray - r.t);
  const Eigen::Vector3d u = s.K * (s.R * world + s.t);
  if (u.z() <= 0) return false;
  *x = u.x() / u.z() - 0.5;
  *y = u.y() / u.z() - 0.5;
  return true;
}

}  // namespace

CostVolumeCL::CostVolumeCL(OpenCLContext* context, StereoCost cost, const CostViewInput& ref,
                           const std::vector<CostViewInput>& sources,
                           OrientationTransfer transfer, int ncc_radius)
    : context_(context), cost_(cost), width_(ref.field.Width()), height_(ref.field.Height()),
      num_views_(static_cast<int>(sources.size())), ncc_radius_(ncc_radius) {
  const int expected_channels = cost == StereoCost::kOrientation ? 2 : 3;
  CHECK_EQ(ref.field.Channels(), expected_channels);
  CHECK_EQ(ref.camera.width, width_);
  CHECK_EQ(ref.camera.height, height_);
  ref_ = ReadOnlyBuffer(context, ref.field.Data());
  std::vector<float> params;
  std::vector<int> dims;
  std::vector<float> all_sources;
  for (const CostViewInput& src : sources) {
    CHECK_EQ(src.field.Channels(), expected_channels);
    CHECK_EQ(src.camera.width, src.field.Width());
    CHECK_EQ(src.camera.height, src.field.Height());
    const ViewProjection projection = ComputeViewProjection(ref.camera, src.camera, transfer);
    const std::array<float, 16> packed =
        projection.Packed(cost == StereoCost::kOrientation ? src.weight : 1.0f);
    params.insert(params.end(), packed.begin(), packed.end());
    const std::array<int, 4> plane =
        ConcatenatedPlaneDims(src.field.Width(), src.field.Height(), all_sources.size());
    dims.insert(dims.end(), plane.begin(), plane.end());
    if (cost == StereoCost::kOrientation) {  // interleaved, as orientation_cost samples it
      const float* re = src.field.Channel(0);
      const float* im = src.field.Channel(1);
      const size_t offset = all_sources.size();
      all_sources.resize(offset + 2 * src.field.NumPixels());
      for (size_t p = 0; p < src.field.NumPixels(); ++p) {
        all_sources[offset + 2 * p] = re[p];
        all_sources[offset + 2 * p + 1] = im[p];
      }
    }
    source_sizes_.push_back({src.field.Width(), src.field.Height()});
    if (cost == StereoCost::kPhotometric) {
      source_buffers_.push_back(ReadOnlyBuffer(context, src.field.Data()));
      source_params_.push_back(ReadOnlyBuffer(context, packed));
    }
  }
  params_ = ReadOnlyBuffer(context, params);
  dims_ = ReadOnlyBuffer(context, dims);
  if (cost == StereoCost::kOrientation) {
    sources_ = ReadOnlyBuffer(context, all_sources);
    orientation_kernel_ = cl::Kernel(CostProgram(context), "orientation_cost");
    const FloatMap& gradient = ref.log_depth_gradient;
    has_gradient_ = gradient.Empty() ? 0 : 1;
    if (has_gradient_) {
      CHECK_EQ(gradient.Width(), width_);
      CHECK_EQ(gradient.Height(), height_);
      CHECK_EQ(gradient.Channels(), 2);
    }
    const float unused[2] = {0, 0};
    log_depth_gradient_ = has_gradient_
                              ? ReadOnlyBuffer(context, gradient.Data())
                              : ReadOnlyBuffer(context, unused, sizeof(unused));
  } else {
    box_ = std::make_unique<BoxFilterCL>(context);
    warp_kernel_ = cl::Kernel(CostProgram(context), "photometric_warp");
    accumulate_kernel_ = cl::Kernel(CostProgram(context), "photometric_accumulate");
    // Reference window statistics: means of R, G, B and of sum_c I_c^2.
    const size_t n = static_cast<size_t>(width_) * height_;
    std::vector<float> planes(4 * n);
    for (size_t p = 0; p < n; ++p) {
      float sq = 0;
      for (int c = 0; c < 3; ++c) {
        const float value = ref.field.Data()[c * n + p];
        planes[c * n + p] = value;
        sq += value * value;
      }
      planes[3 * n + p] = sq;
    }
    cl::Buffer in = ReadOnlyBuffer(context, planes);
    cl::Buffer scratch = context->Buffer(CL_MEM_READ_WRITE, sizeof(float) * planes.size());
    ref_stats_ = context->Buffer(CL_MEM_READ_WRITE, sizeof(float) * planes.size());
    box_->Mean(in, scratch, ref_stats_, width_, height_, 4, ncc_radius_);
    context->Queue().finish();
  }
}

void CostVolumeCL::Compute(const cl::Buffer& label_base, float label_step, int slice_begin,
                           int num_slices, const DepthLabels& labels, const cl::Buffer& out) {
  if (cost_ == StereoCost::kPhotometric) {
    ComputePhotometric(label_base, label_step, slice_begin, num_slices, labels, out);
    return;
  }
  cl::Kernel& k = orientation_kernel_;
  int a = 0;
  k.setArg(a++, ref_);
  k.setArg(a++, width_);
  k.setArg(a++, height_);
  k.setArg(a++, sources_);
  k.setArg(a++, params_);
  k.setArg(a++, dims_);
  k.setArg(a++, num_views_);
  k.setArg(a++, label_base);
  k.setArg(a++, label_step);
  k.setArg(a++, slice_begin);
  k.setArg(a++, num_slices);
  k.setArg(a++, static_cast<float>(labels.a));
  k.setArg(a++, static_cast<float>(labels.b));
  k.setArg(a++, static_cast<int>(labels.inverse));
  k.setArg(a++, out);
  k.setArg(a++, log_depth_gradient_);
  k.setArg(a++, has_gradient_);
  context_->Queue().enqueueNDRangeKernel(
      k, cl::NullRange,
      cl::NDRange(width_, height_, DivideRoundingUp(num_slices, kOrientationSliceChunk)));
}

void CostVolumeCL::ComputePhotometric(const cl::Buffer& label_base, float label_step,
                                      int slice_begin, int num_slices, const DepthLabels& labels,
                                      const cl::Buffer& out) {
  const size_t n = static_cast<size_t>(width_) * height_;
  cl::CommandQueue& queue = context_->Queue();
  queue.enqueueFillBuffer(out, 0.0f, 0, sizeof(float) * n * num_slices);
  if (num_slices > warp_slices_) {
    const size_t bytes = sizeof(float) * 6 * n * num_slices;
    warp_ = context_->Buffer(CL_MEM_READ_WRITE, bytes);
    warp_scratch_ = context_->Buffer(CL_MEM_READ_WRITE, bytes);
    warp_means_ = context_->Buffer(CL_MEM_READ_WRITE, bytes);
    warp_slices_ = num_slices;
  }
  for (int v = 0; v < num_views_; ++v) {
    cl::Kernel& k = warp_kernel_;
    int a = 0;
    k.setArg(a++, ref_);
    k.setArg(a++, width_);
    k.setArg(a++, height_);
    k.setArg(a++, source_buffers_[v]);
    k.setArg(a++, source_sizes_[v][0]);
    k.setArg(a++, source_sizes_[v][1]);
    k.setArg(a++, source_params_[v]);
    k.setArg(a++, label_base);
    k.setArg(a++, label_step);
    k.setArg(a++, slice_begin);
    k.setArg(a++, static_cast<float>(labels.a));
    k.setArg(a++, static_cast<float>(labels.b));
    k.setArg(a++, static_cast<int>(labels.inverse));
    k.setArg(a++, warp_);
    queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(width_, height_, num_slices));
    box_->Mean(warp_, warp_scratch_, warp_means_, width_, height_, 6 * num_slices, ncc_radius_);
    cl::Kernel& acc = accumulate_kernel_;
    acc.setArg(0, ref_stats_);
    acc.setArg(1, warp_means_);
    acc.setArg(2, width_);
    acc.setArg(3, height_);
    acc.setArg(4, out);
    queue.enqueueNDRangeKernel(acc, cl::NullRange, cl::NDRange(width_, height_, num_slices));
  }
}

FloatMap CostVolumeCL::Compute(const std::vector<float>& label_base, float label_step,
                               int slice_begin, int num_slices, const DepthLabels& labels) {
  CHECK_EQ(label_base.size(), static_cast<size_t>(width_) * height_);
  cl::Buffer base = ReadOnlyBuffer(context_, label_base);
  FloatMap out(width_, height_, num_slices);
  cl::Buffer buffer = context_->Buffer(CL_MEM_READ_WRITE, sizeof(float) * out.Data().size());
  Compute(base, label_step, slice_begin, num_slices, labels, buffer);
  context_->Queue().enqueueReadBuffer(buffer, CL_TRUE, 0, sizeof(float) * out.Data().size(),
                                      out.Data().data());
  return out;
}

FloatMap OrientationCostCpu(const CostViewInput& ref, const std::vector<CostViewInput>& sources,
                            const std::vector<float>& label_base, float label_step,
                            int slice_begin, int num_slices, const DepthLabels& labels,
                            OrientationTransfer transfer) {
  const int w = ref.field.Width(), h = ref.field.Height();
  FloatMap out(w, h, num_slices);
  std::vector<double> psi(sources.size(), 0.0);
  for (size_t v = 0; v < sources.size(); ++v) {
    if (transfer == OrientationTransfer::kEpipoleRoll) {
      psi[v] = 2.0 * (EpipoleAngle(ref.camera, sources[v].camera.Center()) -
                      EpipoleAngle(sources[v].camera, ref.camera.Center()));
    }
  }
  for (int k = 0; k < num_slices; ++k) {
    for (int row = 0; row < h; ++row) {
      for (int col = 0; col < w; ++col) {
        const std::complex<double> o_ref(ref.field.At(row, col, 0), ref.field.At(row, col, 1));
        const double label = label_base[row * w + col] + (slice_begin + k) * label_step;
        const double depth = labels.Depth(label);
        const double x_ref = col + 0.5, y_ref = row + 0.5;
        double total = 0;
        for (size_t v = 0; v < sources.size(); ++v) {
          double x, y, re, im = 0;
          if (!ProjectCpu(ref, sources[v], x_ref, y_ref, depth, &x, &y)) continue;
          if (!SampleBilinear(sources[v].field, 0, x, y, &re)) continue;
          SampleBilinear(sources[v].field, 1, x, y, &im);
          const std::complex<double> o_src(re, im);
          std::complex<double> carried = o_ref * std::polar(1.0, -psi[v]);
          if (transfer == OrientationTransfer::kPlaneHomography && std::abs(o_ref) > 0) {
            // The strand through the pixel at angle theta = arg(O_ref) / 2, in its plane:
            // project a short piece of it, both ways. The plane's inverse depth is affine in
            // the image, 1 / z(x + d) = (1 - g . d) / D (g = 0: the fronto-parallel plane).
            const double theta = 0.5 * std::arg(o_ref), step = 1e-3;
            const double dx = step * std::cos(theta), dy = step * std::sin(theta);
            double g_dot_d = 0;
            if (!ref.log_depth_gradient.Empty()) {
              g_dot_d = ref.log_depth_gradient.At(row, col, 0) * dx +
                        ref.log_depth_gradient.At(row, col, 1) * dy;
            }
            double xa, ya, xb, yb;
            ProjectCpu(ref, sources[v], x_ref - dx, y_ref - dy, depth / (1 + g_dot_d), &xa,
                       &ya);
            ProjectCpu(ref, sources[v], x_ref + dx, y_ref + dy, depth / (1 - g_dot_d), &xb,
                       &yb);
            if (xb == xa && yb == ya) continue;  // seen end-on: no direction, no term
            carried = std::polar(std::abs(o_ref), 2.0 * std::atan2(yb - ya, xb - xa));
          }
          total -= sources[v].weight * (std::conj(carried) * o_src).real();
        }
        out.At(row, col, k) = static_cast<float>(total);
      }
    }
  }
  return out;
}

FloatMap PhotometricCostCpu(const CostViewInput& ref, const std::vector<CostViewInput>& sources,
                            const std::vector<float>& label_base, float label_step,
                            int slice_begin, int num_slices, const DepthLabels& labels,
                            int ncc_radius) {
  const int w = ref.field.Width(), h = ref.field.Height();
  FloatMap out(w, h, num_slices);
  for (int k = 0; k < num_slices; ++k) {
    for (size_t v = 0; v < sources.size(); ++v) {
      // Warped source colour at every reference pixel for this slice.
      FloatMap warped(w, h, 3);
      std::vector<char> valid(w * h, 0);
      for (int row = 0; row < h; ++row) {
        for (int col = 0; col < w; ++col) {
          const double depth =
              labels.Depth(label_base[row * w + col] + (slice_begin + k) * label_step);
          double x, y, value;
          if (!ProjectCpu(ref, sources[v], col + 0.5, row + 0.5, depth, &x, &y)) continue;
          if (!SampleBilinear(sources[v].field, 0, x, y, &value)) continue;
          valid[row * w + col] = 1;
          for (int c = 0; c < 3; ++c) {
            SampleBilinear(sources[v].field, c, x, y, &value);
            warped.At(row, col, c) = static_cast<float>(value);
          }
        }
      }
      for (int row = 0; row < h; ++row) {
        for (int col = 0; col < w; ++col) {
          // Zero-mean NCC over the clipped window, colour channels centred separately.
          // Sums of the colours and of their squares (the texture bound below is relative).
          double n = 0, mr[3] = {0, 0, 0}, mv[3] = {0, 0, 0}, square_r = 0, square_v = 0;
          bool all_valid = true;
          const int r0 = std::max(row - ncc_radius, 0), r1 = std::min(row + ncc_radius, h - 1);
          const int c0 = std::max(col - ncc_radius, 0), c1 = std::min(col + ncc_radius, w - 1);
          for (int r = r0; r <= r1; ++r) {
            for (int q = c0; q <= c1; ++q) {
              all_valid = all_valid && valid[r * w + q];
              n += 1;
              for (int c = 0; c < 3; ++c) {
                const double a = ref.field.At(r, q, c), b = warped.At(r, q, c);
                mr[c] += a;
                mv[c] += b;
                square_r += a * a;
                square_v += b * b;
              }
            }
          }
          if (!all_valid) continue;
          for (int c = 0; c < 3; ++c) mr[c] /= n, mv[c] /= n;
          double cross = 0, rr = 0, vv = 0;
          for (int r = r0; r <= r1; ++r) {
            for (int q = c0; q <= c1; ++q) {
              for (int c = 0; c < 3; ++c) {
                const double a = ref.field.At(r, q, c) - mr[c];
                const double b = warped.At(r, q, c) - mv[c];
                cross += a * b;
                rr += a * a;
                vv += b * b;
              }
            }
          }
          // No NCC in a window whose colours vary by less than about 1% of their level
          // (kernels/cost_volume.cl's kMinNccVarianceRatio).
          constexpr double kMinNccVarianceRatio = 1e-4;
          const bool textured =
              rr > kMinNccVarianceRatio * square_r && vv > kMinNccVarianceRatio * square_v;
          out.At(row, col, k) -= static_cast<float>(textured ? cross / std::sqrt(rr * vv) : 0.0);
        }
      }
    }
  }
  return out;
}

SumBestSourcesCL::SumBestSourcesCL(OpenCLContext* context)
    : context_(context), kernel_(CostProgram(context), "sum_best_sources") {}

void SumBestSourcesCL::Run(const cl::Buffer& volumes, int first, int count, int num_best,
                           size_t size, const cl::Buffer& out) {
  CHECK(count >= 1 && num_best >= 1 && num_best <= count);
  kernel_.setArg(0, volumes);
  kernel_.setArg(1, first);
  kernel_.setArg(2, count);
  kernel_.setArg(3, num_best);
  kernel_.setArg(4, static_cast<cl_long>(size));
  kernel_.setArg(5, static_cast<float>(count) / num_best);
  kernel_.setArg(6, out);
  context_->Queue().enqueueNDRangeKernel(kernel_, cl::NullRange, cl::NDRange(size));
}

void SumBestSourcesCpu(const std::vector<float>& volumes, int first, int count, int num_best,
                       size_t size, std::vector<float>* out) {
  std::vector<int> order(count);
  for (size_t i = 0; i < size; ++i) {
    auto value = [&](int c) { return volumes[(first + c) * size + i]; };
    for (int c = 0; c < count; ++c) order[c] = c;
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return value(a) < value(b); });
    std::vector<bool> chosen(count, false);
    for (int j = 0; j < num_best; ++j) chosen[order[j]] = true;
    float sum = 0.0f;
    for (int c = 0; c < count; ++c) {
      if (chosen[c]) sum += value(c);
    }
    (*out)[i] += static_cast<float>(count) / num_best * sum;
  }
}

ResampleAccumulateCL::ResampleAccumulateCL(OpenCLContext* context)
    : context_(context), kernel_(CostProgram(context), "resample_accumulate") {}

void ResampleAccumulateCL::Run(const cl::Buffer& src, int src_width, int src_height,
                               int num_slices, const cl::Buffer& volume, int width, int height,
                               int slice_offset, float scale, float src_pixels_per_pixel) {
  int a = 0;
  kernel_.setArg(a++, src);
  kernel_.setArg(a++, src_width);
  kernel_.setArg(a++, src_height);
  kernel_.setArg(a++, volume);
  kernel_.setArg(a++, width);
  kernel_.setArg(a++, height);
  kernel_.setArg(a++, slice_offset);
  kernel_.setArg(a++, scale);
  kernel_.setArg(a++, src_pixels_per_pixel);
  context_->Queue().enqueueNDRangeKernel(kernel_, cl::NullRange,
                                         cl::NDRange(width, height, num_slices));
}

FloatMap ResampleBilinear(const FloatMap& input, int width, int height,
                          double src_pixels_per_pixel) {
  FloatMap out(width, height, input.Channels());
  const int sw = input.Width(), sh = input.Height();
  for (int c = 0; c < input.Channels(); ++c) {
    for (int row = 0; row < height; ++row) {
      for (int col = 0; col < width; ++col) {
        const double x = std::clamp((col + 0.5) * src_pixels_per_pixel - 0.5, 0.0, sw - 1.0);
        const double y = std::clamp((row + 0.5) * src_pixels_per_pixel - 0.5, 0.0, sh - 1.0);
        double value = 0;
        SampleBilinear(input, c, x, y, &value);
        out.At(row, col, c) = static_cast<float>(value);
      }
    }
  }
  return out;
}

}  // namespace hairmvs
