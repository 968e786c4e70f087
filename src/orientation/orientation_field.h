#pragma once
// The orientation field of one image on an OpenCL device, and its plain CPU reference
// (method.md section 1; paper Section 2). See hairmvs/orientation_fields.h for the options.
//
// Output per level: a 2-channel FloatMap, channel 0 = Re O, channel 1 = Im O, with
//   Theta = argmax_theta |K_theta * I| (first maximum in theta order on ties),
//   F     = (max_theta |K_theta * I|)^gamma,
//   O     = F exp(2 i Theta) if max_theta (K_theta * I) > r max_theta |K_theta * I| and the
//           pixel is not masked, else 0; r = OrientationFieldOptions::SignedResponseRatio():
//           -1 with dark_strands (every pixel with a response), else
//           min_positive_response_ratio (a bright strand: the paper's 0 up to rounding).
// Theta is measured from image +x towards +y (clockwise on screen), modulo pi.
// Levels: level 0 = the input; level k+1 = DownsampleHalf(level k), of size
// ((W_k + 1) / 2, (H_k + 1) / 2); the same fixed-size filters at every level.

#include <memory>
#include <vector>

#include "hairmvs/orientation_fields.h"
#include "src/core/float_map.h"
#include "src/core/timer.h"
#include "src/orientation/filter_bank.h"

namespace hairmvs {

class OpenCLContext;

// 2x2 box average of every channel to ((W + 1) / 2, (H + 1) / 2); at an odd last row/column the
// average of the pixels that exist. The pyramid of the orientation fields and of the
// photometric cost's colour images (StereoCamera::PyramidLevel is its camera).
FloatMap DownsampleHalf(const FloatMap& image);
// The mask of the next level: 1 where the average of the covered mask pixels is >= 0.5
// (a mask pixel counts as valid when > 0), else 0. An empty mask stays empty (= all valid).
FloatMap DownsampleMask(const FloatMap& mask);

// CPU reference for one level, plain loops over the sampled filters in double precision.
// `mask` empty = every pixel valid. If `responses` is not null it receives the signed
// response of every filter (num_orientations maps), for tests.
FloatMap ComputeOrientationLevelReference(const FloatMap& gray, const FloatMap& mask,
                                          const OrientationFilterBank& bank, double gamma,
                                          double signed_response_ratio,
                                          std::vector<FloatMap>* responses = nullptr);
// All levels on the CPU (slow: for tests on small images).
std::vector<FloatMap> ComputeOrientationFieldReference(const FloatMap& gray, const FloatMap& mask,
                                                       const OrientationFieldOptions& options);

// Tunables of the OpenCL kernel (kernels/orientation.cl); the results do not depend on them
// beyond floating-point rounding.
// 8-pixel vectors measured faster than 16 on this 2-core machine through PoCL (2026-12-06,
// alternating in one session): `hairmvs orientation_fields` on synth_straight_gantry's 32 views,
// filter kernel 19.9 / 19.4 s against 21.9 / 21.6 s, the fields byte for byte the same;
// `bench/orientation_benchmark` BM_OrientationFieldAllLevels (block 12, 4 x 4) median 3.91 s
// against 4.43 s.
struct OrientationKernelConfig {
  int vector_width = 8;   // pixels per work-item (8 or 16): the float vector type
  int block_size = 12;    // angles per pass: accumulators kept in registers per work-item
  int local_size_x = 4;   // work-group size (x in work-items, y in rows)
  int local_size_y = 4;
};

// Not thread-safe: one computer per thread (each may share the OpenCLContext only if the
// callers serialise, see src/opencl/opencl_context.h).
class OrientationFieldComputer {
 public:
  OrientationFieldComputer(std::shared_ptr<OpenCLContext> context,
                           const OrientationFieldOptions& options,
                           const OrientationKernelConfig& config = OrientationKernelConfig());
  ~OrientationFieldComputer();

  // `gray` in [0, 1], 1 channel; `mask` empty (all valid) or the same size (> 0 = valid).
  // Returns num_levels 2-channel maps. Device buffers are kept and reused across calls.
  std::vector<FloatMap> Compute(const FloatMap& gray, const FloatMap& mask);
  // One level, no downsampling.
  FloatMap ComputeLevel(const FloatMap& gray, const FloatMap& mask);

  // Stages: "downsample", "upload", "filter kernel", "download". Null = not timed.
  void SetTimings(StageTimings* timings) { timings_ = timings; }
  const OrientationFilterBank& Bank() const { return bank_; }

 private:
  struct DeviceState;
  std::shared_ptr<OpenCLContext> context_;
  OrientationFieldOptions options_;
  OrientationKernelConfig config_;
  OrientationFilterBank bank_;
  BlockedFilterBank blocked_;
  std::unique_ptr<DeviceState> state_;
  StageTimings* timings_ = nullptr;
};

}  // namespace hairmvs
