#include "src/orientation/orientation_field.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "src/core/logging.h"
#include "src/opencl/opencl_context.h"

namespace hairmvs {
namespace {

void CheckInputs(const FloatMap& gray, const FloatMap& mask) {
  THROW_IF(gray.Empty() || gray.Channels() != 1,
           "Orientation field: expected a non-empty 1-channel grey image, got "
               << gray.Width() << "x" << gray.Height() << "x" << gray.Channels());
  THROW_IF(!mask.Empty() && (mask.Width() != gray.Width() || mask.Height() != gray.Height() ||
                             mask.Channels() != 1),
           "Orientation field: the mask is " << mask.Width() << "x" << mask.Height() << "x"
                                             << mask.Channels() << ", the image " << gray.Width()
                                             << "x" << gray.Height() << "x1");
}

}  // namespace

FloatMap DownsampleHalf(const FloatMap& image) {
  const int w = (image.Width() + 1) / 2, h = (image.Height() + 1) / 2;
  FloatMap out(w, h, image.Channels());
  for (int c = 0; c < image.Channels(); ++c) {
    for (int row = 0; row < h; ++row) {
      for (int col = 0; col < w; ++col) {
        float sum = 0;
        int count = 0;
        for (int r = 2 * row; r < std::min(2 * row + 2, image.Height()); ++r) {
          for (int q = 2 * col; q < std::min(2 * col + 2, image.Width()); ++q) {
            sum += image.At(r, q, c);
            ++count;
          }
        }
        out.At(row, col, c) = sum / count;
      }
    }
  }
  return out;
}

FloatMap DownsampleMask(const FloatMap& mask) {
  if (mask.Empty()) return mask;
  FloatMap binary(mask.Width(), mask.Height(), 1);
  for (int row = 0; row < mask.Height(); ++row) {
    for (int col = 0; col < mask.Width(); ++col) {
      binary.At(row, col) = mask.At(row, col) > 0 ? 1.0f : 0.0f;
    }
  }
  FloatMap out = DownsampleHalf(binary);
  for (float& v : out.Data()) v = v >= 0.5f ? 1.0f : 0.0f;
  return out;
}

FloatMap ComputeOrientationLevelReference(const FloatMap& gray, const FloatMap& mask,
                                          const OrientationFilterBank& bank, double gamma,
                                          double signed_response_ratio,
                                          std::vector<FloatMap>* responses) {
  CheckInputs(gray, mask);
  const int w = gray.Width(), h = gray.Height(), n = bank.NumOrientations();
  if (responses != nullptr) responses->assign(n, FloatMap(w, h, 1));
  FloatMap out(w, h, 2);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      double best_abs = -1, max_signed = -INFINITY;
      int best_k = 0;
      for (int k = 0; k < n; ++k) {
        double response = 0;
        for (const FilterTap& tap : bank.Taps(k)) {
          // Replicated borders.
          const int r = std::clamp(row + tap.dy, 0, h - 1);
          const int q = std::clamp(col + tap.dx, 0, w - 1);
          response += static_cast<double>(tap.weight) * gray.At(r, q);
        }
        if (responses != nullptr) (*responses)[k].At(row, col) = static_cast<float>(response);
        if (std::abs(response) > best_abs) {
          best_abs = std::abs(response);
          best_k = k;
        }
        max_signed = std::max(max_signed, response);
      }
      const bool valid = max_signed > signed_response_ratio * best_abs &&
                         (mask.Empty() || mask.At(row, col) > 0);
      if (!valid) continue;
      const double confidence = std::pow(best_abs, gamma);
      const double two_theta = 2.0 * bank.ThetaRad(best_k);
      out.At(row, col, 0) = static_cast<float>(confidence * std::cos(two_theta));
      out.At(row, col, 1) = static_cast<float>(confidence * std::sin(two_theta));
    }
  }
  return out;
}

std::vector<FloatMap> ComputeOrientationFieldReference(const FloatMap& gray, const FloatMap& mask,
                                                       const OrientationFieldOptions& options) {
  const OrientationFilterBank bank(options);
  std::vector<FloatMap> levels;
  FloatMap level_gray = gray, level_mask = mask;
  for (int l = 0; l < options.num_levels; ++l) {
    if (l > 0) {
      level_gray = DownsampleHalf(level_gray);
      level_mask = DownsampleMask(level_mask);
    }
    levels.push_back(
        ComputeOrientationLevelReference(level_gray, level_mask, bank, options.confidence_gamma,
                                         options.SignedResponseRatio()));
  }
  return levels;
}

struct OrientationFieldComputer::DeviceState {
  cl::Kernel kernel;
  cl::Buffer tap_begin, weights;
  // Resized only when an image needs more room, so a sequence of images reuses them.
  cl::Buffer padded, tap_offsets, mask, out;
  size_t padded_capacity = 0, mask_capacity = 0, out_capacity = 0;
  int tap_offsets_stride = -1;
  // Host staging, reused.
  std::vector<float> padded_host, mask_host, out_host;
  std::vector<int> tap_offsets_host;
};

OrientationFieldComputer::OrientationFieldComputer(std::shared_ptr<OpenCLContext> context,
                                                   const OrientationFieldOptions& options,
                                                   const OrientationKernelConfig& config)
    : context_(std::move(context)),
      options_(options),
      config_(config),
      bank_(options),
      blocked_(MakeBlockedFilterBank(bank_, config.block_size)),
      state_(std::make_unique<DeviceState>()) {
  CHECK(context_ != nullptr);
  THROW_IF(config_.vector_width != 8 && config_.vector_width != 16,
           "OrientationKernelConfig: vector_width must be 8 or 16");
  THROW_IF(config_.block_size < 1 || config_.block_size > 32,
           "OrientationKernelConfig: block_size must be in [1, 32]");
  std::ostringstream build_options;
  build_options << "-D VEC=" << config_.vector_width << " -D BLOCK=" << config_.block_size;
  cl::Program& program = context_->Program({"orientation.cl"}, build_options.str());
  state_->kernel = cl::Kernel(program, "orientation_field");
  state_->tap_begin = ReadOnlyBuffer(context_.get(), blocked_.tap_begin);
  state_->weights = ReadOnlyBuffer(context_.get(), blocked_.weights);
}

OrientationFieldComputer::~OrientationFieldComputer() = default;

std::vector<FloatMap> OrientationFieldComputer::Compute(const FloatMap& gray,
                                                       const FloatMap& mask) {
  CheckInputs(gray, mask);
  std::vector<FloatMap> levels;
  FloatMap level_gray, level_mask;
  for (int l = 0; l < options_.num_levels; ++l) {
    if (l > 0) {
      ScopedStageTimer timer(timings_, "downsample");
      level_gray = DownsampleHalf(l == 1 ? gray : level_gray);
      level_mask = DownsampleMask(l == 1 ? mask : level_mask);
    }
    levels.push_back(ComputeLevel(l == 0 ? gray : level_gray, l == 0 ? mask : level_mask));
  }
  return levels;
}

FloatMap OrientationFieldComputer::ComputeLevel(const FloatMap& gray, const FloatMap& mask) {
  CheckInputs(gray, mask);
  DeviceState& s = *state_;
  cl::CommandQueue& queue = context_->Queue();
  const int w = gray.Width(), h = gray.Height();
  FloatMap out(w, h, 2);
  // Only the mask's bounding box is filtered: the field is 0 outside the mask anyway, and the
  // shared sets' masks (hair and head) cover a fifth of their views, their boxes under a third.
  // The box's inputs within the filters' reach are the image's own pixels (replicated at the
  // image's edges, not the box's), so the box's field is the whole image's, byte for byte.
  const PixelBox box = mask.Empty() ? PixelBox{0, 0, w, h} : BoundingBoxAbove(mask, 0.0f);
  if (box.Empty()) return out;
  const int vec = config_.vector_width;
  const int pad = bank_.Radius();
  const int out_stride = static_cast<int>(RoundUpToMultiple(box.width, vec));
  const int padded_stride = out_stride + 2 * pad;
  const int padded_rows = box.height + 2 * pad;

  {
    ScopedStageTimer timer(timings_, "upload");
    // The box and `pad` pixels around it, with the image's edges replicated (also the columns
    // past the box up to out_stride, which the last work-item of a row computes and the host
    // discards).
    s.padded_host.resize(static_cast<size_t>(padded_stride) * padded_rows);
    for (int r = 0; r < padded_rows; ++r) {
      const float* src = gray.Channel(0) +
                         static_cast<size_t>(std::clamp(box.y0 + r - pad, 0, h - 1)) * w;
      float* dst = s.padded_host.data() + static_cast<size_t>(r) * padded_stride;
      for (int c = 0; c < padded_stride; ++c) {
        dst[c] = src[std::clamp(box.x0 + c - pad, 0, w - 1)];
      }
    }
    s.mask_host.assign(static_cast<size_t>(out_stride) * box.height, 0.0f);
    for (int r = 0; r < box.height; ++r) {
      float* dst = s.mask_host.data() + static_cast<size_t>(r) * out_stride;
      if (mask.Empty()) {
        std::fill(dst, dst + box.width, 1.0f);
      } else {
        const float* src = mask.Channel(0) + static_cast<size_t>(box.y0 + r) * w + box.x0;
        std::copy(src, src + box.width, dst);
      }
    }
    const size_t padded_bytes = s.padded_host.size() * sizeof(float);
    if (padded_bytes > s.padded_capacity) {
      s.padded = context_->Buffer(CL_MEM_READ_ONLY, padded_bytes);
      s.padded_capacity = padded_bytes;
    }
    const size_t mask_bytes = s.mask_host.size() * sizeof(float);
    if (mask_bytes > s.mask_capacity) {
      s.mask = context_->Buffer(CL_MEM_READ_ONLY, mask_bytes);
      s.mask_capacity = mask_bytes;
    }
    const size_t out_bytes = 2 * mask_bytes;
    if (out_bytes > s.out_capacity) {
      s.out = context_->Buffer(CL_MEM_WRITE_ONLY, out_bytes);
      s.out_capacity = out_bytes;
    }
    if (padded_stride != s.tap_offsets_stride) {
      s.tap_offsets_host.resize(blocked_.tap_dx.size());
      for (size_t t = 0; t < blocked_.tap_dx.size(); ++t) {
        s.tap_offsets_host[t] = blocked_.tap_dy[t] * padded_stride + blocked_.tap_dx[t];
      }
      s.tap_offsets = ReadOnlyBuffer(context_.get(), s.tap_offsets_host);
      s.tap_offsets_stride = padded_stride;
    }
    queue.enqueueWriteBuffer(s.padded, CL_FALSE, 0, padded_bytes, s.padded_host.data());
    queue.enqueueWriteBuffer(s.mask, CL_FALSE, 0, mask_bytes, s.mask_host.data());
    queue.finish();
  }

  {
    ScopedStageTimer timer(timings_, "filter kernel");
    cl::Kernel& k = s.kernel;
    int arg = 0;
    k.setArg(arg++, s.padded);
    k.setArg(arg++, padded_stride);
    k.setArg(arg++, pad);
    k.setArg(arg++, s.tap_offsets);
    k.setArg(arg++, s.tap_begin);
    k.setArg(arg++, s.weights);
    k.setArg(arg++, s.mask);
    k.setArg(arg++, s.out);
    k.setArg(arg++, blocked_.num_blocks);
    k.setArg(arg++, blocked_.num_orientations);
    k.setArg(arg++, box.width);
    k.setArg(arg++, box.height);
    k.setArg(arg++, out_stride);
    k.setArg(arg++, static_cast<float>(options_.confidence_gamma));
    k.setArg(arg++, static_cast<float>(options_.SignedResponseRatio()));
    const cl::NDRange local(config_.local_size_x, config_.local_size_y);
    const cl::NDRange global(RoundUpToMultiple(out_stride / vec, config_.local_size_x),
                             RoundUpToMultiple(box.height, config_.local_size_y));
    queue.enqueueNDRangeKernel(k, cl::NullRange, global, local);
    queue.finish();
  }

  {
    ScopedStageTimer timer(timings_, "download");
    s.out_host.resize(2 * static_cast<size_t>(out_stride) * box.height);
    queue.enqueueReadBuffer(s.out, CL_TRUE, 0, s.out_host.size() * sizeof(float),
                            s.out_host.data());
    for (int c = 0; c < 2; ++c) {
      for (int r = 0; r < box.height; ++r) {
        const float* src =
            s.out_host.data() + (static_cast<size_t>(c) * box.height + r) * out_stride;
        std::copy(src, src + box.width,
                  out.Channel(c) + static_cast<size_t>(box.y0 + r) * w + box.x0);
      }
    }
  }
  return out;
}

}  // namespace hairmvs
