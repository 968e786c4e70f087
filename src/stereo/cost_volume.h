#pragma once
// Matching-cost volumes for one reference view at one pyramid level, on the device
// (kernels/cost_volume.cl), one launch per block of depth slices.
//  - orientation (paper Eq. 4-5): e(p, D) = sum_v -Re(O_ref(p)* O_v(P_v(p, D)) exp(2i(phi_ref -
//    phi_v))), O_v sampled bilinearly at the level's resolution; views where P_v(p, D) falls
//    outside the image add nothing. Bilinear sampling damps a band-pass field most half-way
//    between pixels, which could pull the depths towards whole-pixel disparities; Catmull-Rom
//    sampling instead (a prototype at stop 56) gave the g2 group of synth_straight_gantry 4.01
//    mm against 4.02 (the data term alone 4.54 against 4.56 mm): no such pull to speak of;
//  - photometric baseline: e(p, D) = -sum_v NCC_v(p, D), the zero-mean NCC of the colour windows
//    (fronto-parallel in depth-label space), O(1) per pixel with box filters.
// Slice k of a block is label v = label_base[p] + (slice_begin + k) * label_step.

#include <memory>
#include <utility>
#include <vector>

#include "hairmvs/orientation_stereo.h"
#include "src/core/float_map.h"
#include "src/opencl/opencl.h"
#include "src/stereo/guided_filter.h"
#include "src/stereo/stereo_geometry.h"

namespace hairmvs {

class OpenCLContext;

// A view at one level: its camera on the field's grid (a pyramid level's:
// StereoCamera::PyramidLevel) and its field: orientation (2 channels) or colour (3 channels).
struct CostViewInput {
  CostViewInput() = default;
  CostViewInput(const StereoCamera& camera_in, FloatMap field_in,
                FloatMap log_depth_gradient_in = FloatMap())
      : camera(camera_in), field(std::move(field_in)),
        log_depth_gradient(std::move(log_depth_gradient_in)) {}

  StereoCamera camera;
  FloatMap field;
  // The reference's, for the plane_homography transfer: the gradient of log depth of the plane
  // its strands lie in, per pixel (LogDepthGradient; 2 channels). Empty: fronto-parallel.
  FloatMap log_depth_gradient;
  // A source's factor in the orientation cost's sum over the sources (the photometric cost
  // ignores it): OrientationStereoOptions::LevelSourceWeight.
  float weight = 1.0f;
};

class CostVolumeCL {
 public:
  CostVolumeCL(OpenCLContext* context, StereoCost cost, const CostViewInput& ref,
               const std::vector<CostViewInput>& sources, OrientationTransfer transfer,
               int ncc_radius = 3);
  int Width() const { return width_; }
  int Height() const { return height_; }
  // label_base: width * height floats on the device. out: num_slices planes.
  void Compute(const cl::Buffer& label_base, float label_step, int slice_begin, int num_slices,
               const DepthLabels& labels, const cl::Buffer& out);
  // Host convenience (tests): label_base of width * height floats; returns num_slices channels.
  FloatMap Compute(const std::vector<float>& label_base, float label_step, int slice_begin,
                   int num_slices, const DepthLabels& labels);

 private:
  void ComputePhotometric(const cl::Buffer& label_base, float label_step, int slice_begin,
                          int num_slices, const DepthLabels& labels, const cl::Buffer& out);

  OpenCLContext* context_;
  StereoCost cost_;
  int width_ = 0;
  int height_ = 0;
  int num_views_ = 0;
  int ncc_radius_ = 3;
  cl::Buffer ref_;
  cl::Buffer sources_;
  cl::Buffer params_;
  cl::Buffer dims_;
  cl::Buffer log_depth_gradient_;  // 2 planes, or 2 floats unused when has_gradient_ is 0
  int has_gradient_ = 0;
  std::vector<std::array<int, 2>> source_sizes_;
  std::vector<cl::Buffer> source_buffers_;  // photometric: one colour image per view
  std::vector<cl::Buffer> source_params_;   // photometric: 16 floats per view
  cl::Buffer ref_stats_;                    // photometric: window means of the reference
  cl::Buffer warp_, warp_scratch_, warp_means_;
  int warp_slices_ = 0;
  std::unique_ptr<BoxFilterCL> box_;
  cl::Kernel orientation_kernel_;
  cl::Kernel warp_kernel_;
  cl::Kernel accumulate_kernel_;
};

// Plain CPU references (tests): the same costs, projecting each pixel through the world frame
// (X = R_ref^T (D K_ref^-1 x - t_ref), u = K_v (R_v X + t_v)) in double precision; photometric
// windows summed explicitly.
FloatMap OrientationCostCpu(const CostViewInput& ref, const std::vector<CostViewInput>& sources,
                            const std::vector<float>& label_base, float label_step,
                            int slice_begin, int num_slices, const DepthLabels& labels,
                            OrientationTransfer transfer);
FloatMap PhotometricCostCpu(const CostViewInput& ref, const std::vector<CostViewInput>& sources,
                            const std::vector<float>& label_base, float label_step,
                            int slice_begin, int num_slices, const DepthLabels& labels,
                            int ncc_radius);

// Adds `scale` times `num_slices` planes of (src_width, src_height), bilinearly resampled to the
// (width, height) grid, into slices [slice_offset, ...) of `volume`. Both grids are pyramid
// levels: they start at the image origin and an output pixel is src_pixels_per_pixel source
// pixels wide (2^(output level - source level)).
class ResampleAccumulateCL {
 public:
  explicit ResampleAccumulateCL(OpenCLContext* context);
  void Run(const cl::Buffer& src, int src_width, int src_height, int num_slices,
           const cl::Buffer& volume, int width, int height, int slice_offset, float scale,
           float src_pixels_per_pixel);

 private:
  OpenCLContext* context_;
  cl::Kernel kernel_;
};

// best_source_fraction (kernels/cost_volume.cl): out[i] += count / num_best x the sum of the
// num_best lowest of volumes[(first + c) * size + i] over c < count (ties to the lower c), for
// i < size: `volumes` holds the sources' volumes one after another.
class SumBestSourcesCL {
 public:
  explicit SumBestSourcesCL(OpenCLContext* context);
  void Run(const cl::Buffer& volumes, int first, int count, int num_best, size_t size,
           const cl::Buffer& out);

 private:
  OpenCLContext* context_;
  cl::Kernel kernel_;
};

// The same in plain C++ (the kernel's test reference): the lowest chosen by a stable sort.
void SumBestSourcesCpu(const std::vector<float>& volumes, int first, int count, int num_best,
                       size_t size, std::vector<float>* out);

// Bilinear resampling of every channel to width x height, an output pixel being
// src_pixels_per_pixel input pixels wide from the same origin (pyramid levels; SfM centres,
// clamped at the border): the CPU twin of resample_accumulate.
FloatMap ResampleBilinear(const FloatMap& input, int width, int height,
                          double src_pixels_per_pixel);

}  // namespace hairmvs
