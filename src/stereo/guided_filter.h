#pragma once
// Structure-aware aggregation (paper Eq. 7-8): a guided filter (He et al. 2010) whose guide is
// the 2-channel orientation field (Re O, Im O) with an isotropic variance, so that costs are
// averaged along strands (similar O) and not across them. O(1) per pixel with running-sum box
// filters (kernels/guided_filter.cl). Windows are clipped at the image border.

#include <memory>

#include "src/core/float_map.h"
#include "src/opencl/opencl.h"

namespace hairmvs {

class OpenCLContext;

// Window means of every plane of `in` (planar, num_planes planes of width x height) into `out`
// (may be `in` itself: rows go in -> scratch, columns scratch -> out), on the device.
class BoxFilterCL {
 public:
  explicit BoxFilterCL(OpenCLContext* context);
  void Mean(const cl::Buffer& in, const cl::Buffer& scratch, const cl::Buffer& out, int width,
            int height, int num_planes, int radius);

 private:
  OpenCLContext* context_;
  cl::Kernel rows_;
  cl::Kernel cols_;
};

class GuidedFilterCL {
 public:
  // guide: 2 channels (Re O, Im O) of the level. radius: window (2 radius + 1)^2.
  GuidedFilterCL(OpenCLContext* context, const FloatMap& guide, int radius, float eps);
  // Filters num_slices planes of `in` (width x height each) into `out` (may alias `in`).
  void Filter(const cl::Buffer& in, int num_slices, const cl::Buffer& out);
  // Host convenience: filters every channel of `input`.
  FloatMap Filter(const FloatMap& input);

  int Width() const { return width_; }
  int Height() const { return height_; }

 private:
  void EnsureScratch(int num_slices);

  OpenCLContext* context_;
  int width_;
  int height_;
  int radius_;
  BoxFilterCL box_;
  cl::Buffer guide_;
  cl::Buffer stats_;
  cl::Buffer planes_;
  cl::Buffer scratch_;
  int scratch_slices_ = 0;
  cl::Kernel products_;
  cl::Kernel coefficients_;
  cl::Kernel output_;
};

// Plain CPU references (tests): window means by explicit sums over the clipped window, and the
// guided filter computed window by window (a_k, b_k from explicit sums, then averaged over the
// windows containing each pixel), in double precision.
FloatMap BoxMeanCpu(const FloatMap& input, int radius);
FloatMap GuidedFilterCpu(const FloatMap& guide, const FloatMap& input, int radius, double eps);

}  // namespace hairmvs
