#pragma once
// The depth map of one reference view from prepared per-level data (method.md section 2):
// cost volumes per level and block of depth slices, guided-filter aggregation per level,
// the levels summed on the MRF grid, the MRF solved coarse to fine, sub-pixel refinement and the
// final guided filter. Knows nothing of workspaces or files (orientation_stereo.cc does).

#include <vector>

#include "colmap_ext/mat_io.h"
#include "hairmvs/orientation_stereo.h"
#include "src/core/float_map.h"
#include "src/core/timer.h"
#include "src/fusion/fusion_view.h"
#include "src/stereo/geometric_prior.h"
#include "src/stereo/stereo_geometry.h"

namespace hairmvs {

class OpenCLContext;
class Progress;

struct StereoViewData {
  StereoCamera camera;                 // at the processing resolution (= level 0)
  std::vector<FloatMap> orientation;   // per level, 2 channels (Re O, Im O)
  // What the orientation cost matches, per level: `orientation` itself (the paper), or its
  // local normalisation (NormalizeOrientationField). Empty = `orientation`. The guide of the
  // aggregation and the smoothness weights always use `orientation`.
  std::vector<FloatMap> matching;
  std::vector<FloatMap> rgb;           // per level, 3 channels (costs that match colours)
};

// Local normalisation of an orientation field for matching: (O - mean_w(O)) / sqrt(mean_w(|O -
// mean_w(O)|^2) + eps), window (2 radius + 1)^2, 0 where O = 0 (masked or dark pixels), eps =
// relative_eps x MeanSquareOfNonZero(orientation). The paper's cost -Re(O_ref* O_v) is a
// product of confidences, so bright, high-contrast regions of a source view win whatever their
// alignment; normalised fields make the aggregated cost a correlation of the orientation
// textures (a zero-mean NCC of the complex fields).
FloatMap NormalizeOrientationField(const FloatMap& orientation, int radius, float relative_eps);

// The mean over the pixels where it is non-zero of the squared magnitude (summed over the
// channels); 0 when every pixel is zero.
double MeanSquareOfNonZero(const FloatMap& field);

// `field` scaled so that the RMS magnitude of its non-zero pixels is `rms` (unchanged when all
// are zero).
FloatMap ScaleToRms(const FloatMap& field, double rms);

// The pyramid levels that the reference and every source have (orientation fields, and colour
// images if `colour`).
int CommonPyramidLevels(const StereoViewData& ref,
                        const std::vector<const StereoViewData*>& sources, bool colour);

// The scale at which `source` images the point of the reference's centre ray at the depth
// range's middle label, against the reference's (ImageScaleRatio; 0 where it lies behind it).
double SourceScaleRatio(const StereoViewData& ref, const StereoViewData& source,
                        const DepthLabels& labels);

// The offset from the reference's pyramid level to the source's level that images the hair at
// its scale, for a source at `ratio` (SourceScaleRatio): round(log2 ratio), so that the
// filter bank's bands in pixels cover the same strands. 0 unless match_scale and ratio > 0.
int SourceLevelOffset(double ratio, bool match_scale);

// The source's pyramid level that the reference's `level` meets: level + offset, clamped to
// the levels the source has (of its orientation fields, and of its colour images if `colour`).
int SourceLevel(const StereoViewData& source, int level, int offset, bool colour);

// How far off the reference's scale the best-matched of the source's levels that the
// reference's first num_levels levels meet images the hair: the least over those levels l of
// max(r, 1 / r), r = ratio / 2^(SourceLevel(source, l, offset, colour) - l), `ratio` from
// SourceScaleRatio; 0 where ratio <= 0.
double BestLevelScaleMismatch(const StereoViewData& source, double ratio, int offset,
                              bool colour, int num_levels);

struct DepthEstimate {
  FloatMap depth;       // z-depth on the level-0 grid, 0 = invalid
  FloatMap confidence;  // aggregated cost margin (second-best minus best), level-0 grid
  double coarse_energy = 0;
  double fine_energy = 0;
  int num_valid = 0;
  // The mask's pixels, and those of them that lie outside the range: at its first label, or at
  // its last or with the visual hull's entry behind it (labels dropped with filter_range_ends,
  // and entries whose fine band the range clamps, then dropped by the hull's bound). Many such
  // pixels say the range cuts the hair off.
  int num_in_mask = 0;
  int num_at_near_end = 0;
  int num_at_far_end = 0;
  // The labels' disparity step (LabelStepPxPerRadian) and the smoothness weight it gave
  // (OrientationStereoOptions::ViewLambda).
  double label_step_px = 0;
  double lambda = 0;
  // With options.write_cost_volume and no prior: the coarse stage's aggregated data term
  // before any prior or bound (coarse grid, one channel per label) and each label's depth.
  CostVolume coarse_data_term;
};

// Depth slices per block of the cost volume and aggregation: slice_block, at most num_labels
// and at least 1, and fewer where a block's largest buffer (`bytes_per_slice` per slice) would
// exceed the device's largest allocation, `max_alloc_bytes` (a GPU's is often a quarter of its
// memory); 1 even where one slice does not fit (its buffer's error then says so).
int SliceBlockThatFits(int slice_block, int num_labels, size_t bytes_per_slice,
                       size_t max_alloc_bytes);

// `coarse_volume_cache` (may be null): the coarse stage's aggregated data term, before any
// prior or bound, which depends only on the views, labels and options; used (and emptied) when
// it holds a volume of the coarse grid's size, filled when empty (the geometric pass estimates
// each view again from the same data: the all-label volume is most of an estimate's work).
// `visual_hull_entry` (level-0 grid, metres, 0 = none; may be empty): where each pixel's ray
// enters the masks' visual hull. Less options.visual_hull_tolerance_m it bounds the depth, per
// options.visual_hull_depth_bound: kFilter, depths that end in front of it are invalid (0);
// kPenalty, labels in front of it get the pixel's worst cost plus one cost range per label of
// excess, in both stages. Its tilt gives the strands' plane (strand_plane_from_visual_hull).
DepthEstimate EstimateDepthMap(OpenCLContext* context, const StereoViewData& ref,
                               const std::vector<const StereoViewData*>& sources,
                               const FloatMap& mask, const FloatMap& visual_hull_entry,
                               const DepthLabels& labels,
                               const OrientationStereoOptions& options, StageTimings* timings,
                               Progress* progress = nullptr,
                               const GeometricPrior* prior = nullptr,
                               std::vector<float>* coarse_volume_cache = nullptr);

// Paper Eq. 9: sub-label offsets (in labels, within [-0.5, 0.5]) from the costs at each pixel's
// label and its two neighbours. volume: [label][pixel]; labels at either end get 0.
std::vector<float> SubpixelOffsets(const std::vector<float>& volume, int num_pixels,
                                   int num_labels, const std::vector<int>& labels);

// MRF smoothness weights of paper Eq. 3: lambda * exp(-|O(p) - O(q)|^2 / (2 sigma_o^2)) for
// q = p + x (right) and p + y (down).
void SmoothnessWeights(const FloatMap& orientation, double lambda, double sigma_o,
                       std::vector<float>* weight_right, std::vector<float>* weight_down);

}  // namespace hairmvs
