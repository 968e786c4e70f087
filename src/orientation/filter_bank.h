#pragma once
// The sampled filter bank of the orientation field (method.md section 1, paper Section 2).
//
// K_theta(dx, dy) = (G_inner(across) - G_outer(across)) G_along(along), with
//   along  =  dx cos(theta) + dy sin(theta)   (the filter's long axis = the strand direction),
//   across = -dx sin(theta) + dy cos(theta),
// theta = k pi / num_orientations, measured from image +x (columns) towards +y (rows).
// (dx, dy) are integer pixel offsets; the response at pixel p is sum K(d) I(p + d) (a
// correlation; K(-d) = K(d), so also a convolution). Borders: replicate the edge pixels.

#include <vector>

#include "hairmvs/orientation_fields.h"

namespace hairmvs {

struct FilterTap {
  int dx = 0;
  int dy = 0;
  float weight = 0;
};

class OrientationFilterBank {
 public:
  explicit OrientationFilterBank(const OrientationFieldOptions& options);

  int NumOrientations() const { return static_cast<int>(taps_.size()); }
  // Angle of filter k in radians, modulo pi.
  double ThetaRad(int k) const;
  // Every tap of filter k (both d and -d; the centre once).
  const std::vector<FilterTap>& Taps(int k) const { return taps_[k]; }
  // The largest |dx| or |dy| of any tap.
  int Radius() const { return radius_; }

 private:
  std::vector<std::vector<FilterTap>> taps_;
  int radius_ = 0;
};

// The filters grouped in blocks of `block_size` consecutive angles for the OpenCL kernel:
// within a block, each tap pair {d, -d} of the union of the block's supports carries one
// weight per angle of the block (0 where an angle's support lacks it), so one pair of loads
// feeds block_size multiply-adds. The centre tap is the pair {0, 0} with half its weight.
struct BlockedFilterBank {
  int block_size = 0;
  int num_blocks = 0;        // ceil(num_orientations / block_size); the last is zero-padded
  int num_orientations = 0;
  std::vector<int> tap_begin;  // num_blocks + 1 entries: taps of block b are [begin[b], begin[b+1])
  std::vector<int> tap_dx, tap_dy;  // one offset of each pair (dy > 0, or dy == 0 and dx >= 0)
  std::vector<float> weights;     // [tap][block_size]
};
BlockedFilterBank MakeBlockedFilterBank(const OrientationFilterBank& bank, int block_size);

}  // namespace hairmvs
