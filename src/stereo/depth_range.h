#pragma once
// Depth range of a reference view from the masks' visual hull: the depths along the rays of
// the reference's masked pixels whose 3D points every other view that sees them keeps in its
// mask. For hair captured in a textured room the sparse points (COLMAP's range rule) lie
// mostly on the room, giving ranges several times deeper than the head; the hull is tight.

#include <utility>
#include <vector>

#include "colmap_ext/source_views.h"
#include "src/core/float_map.h"
#include "src/stereo/stereo_geometry.h"

namespace hairmvs {

struct VisualHullRangeOptions {
  // Reference pixels sampled: every pixel_step-th column and row inside the mask.
  int pixel_step = 8;
  // VisualHullIntervals: also find where each ray leaves the hull. Without, the far channel is
  // 0: walking through the hull checks every view at every sample, most of the cost
  // (synth_straight_gantry: 1.1 s per 960 x 640 view with 31 others).
  bool find_far_ends = true;
  // Depth samples per ray, uniform in inverse depth over the search range.
  int num_samples = 256;
  // Percentiles (0-100) of the kept depths that give the range (robust to stray samples).
  double low_percentile = 1;
  double high_percentile = 99;
  // Each end widened by max(margin_fraction * (max - min), margin_m). 0.15 rather than 0.05:
  // the percentiles trim some true depths (gantry g0_c,g0_l median 6.02 mm with 0.05, 5.89
  // with 0.15; handheld h00-h15 45.8 vs 41.4 mm).
  double margin_fraction = 0.15;
  double margin_m = 0.005;
  // A depth sample is kept only if at least this many other views (capped at their number)
  // see it inside their image, and all of those inside their mask: a sample seen by one view
  // only is carved by one epipolar line, which crosses that view's mask over long stretches
  // when the two views are close (handheld h10: 0.21-5.03 m with 1, 0.42-0.67 m with 3).
  int min_observing_views = 3;
  // A depth sample is carved only when at least this many of the views that see it have it
  // outside their mask (capped at their number): 1 is the strict hull; 2 lets no single view
  // with a wrong pose or a wrong mask carve away what the others keep.
  int min_carving_views = 1;
  // Fewer sampled rays entering the hull than this: no range (returns false).
  int min_rays_in_hull = 4;
};

// Per pixel of the reference (every options.pixel_step-th column and row inside its mask), the
// first stretch of its ray inside the hull: a 2-channel map (near, far) in metres at the
// reference's size, (0, 0) where not sampled or where the ray never enters the hull. The near
// end is a lower bound on the depth of whatever the pixel sees: the first surface along the ray
// lies inside every mask that sees it, hence inside the hull. (The far end is no such bound: a
// phantom stretch of hull, carved by no view, may lie in front of the surface.) The ends are
// refined by bisection between the depth samples; the far ends only with
// options.find_far_ends. *near_end_causes (if given): per sampled pixel whose ray enters the
// hull, what ends the hull in front of its near end (NearEndCause as a float; 0 elsewhere).
enum class NearEndCause {
  kNone = 0,
  kSearchStart = 1,  // inside the hull at the search's first sample
  kFrusta = 2,       // the sample in front seen by too few views
  kMasks = 3,        // the sample in front carved by the masks
};
FloatMap VisualHullIntervals(const StereoCamera& ref, const FloatMap& ref_mask,
                             const std::vector<std::pair<StereoCamera, FloatMap>>& others,
                             double search_min_m, double search_max_m,
                             const VisualHullRangeOptions& options = VisualHullRangeOptions(),
                             FloatMap* near_end_causes = nullptr);

// Where VisualHullDepthRange's hull begins.
struct HullNearEnd {
  // The low percentile of the rays' near ends is the search's start: the hull may go on in
  // front of it.
  bool at_search_start = false;
  // Of the rays entering the hull after the search's start, the fraction whose near end the
  // masks cut (NearEndCause::kMasks).
  double fraction_cut_by_masks = 0;
};

// Masks are 1 = keep, 0 = excluded, each at its camera's width x height; cameras in the SfM
// pixel convention. The range spans the percentiles of the near ends (low) and far ends (high)
// of VisualHullIntervals (with far ends), sampled every options.pixel_step pixels. Returns false
// (outputs untouched) when too few rays enter the hull; *near_end (if given) says where it
// begins.
bool VisualHullDepthRange(const StereoCamera& ref, const FloatMap& ref_mask,
                          const std::vector<std::pair<StereoCamera, FloatMap>>& others,
                          double search_min_m, double search_max_m, double* min_m,
                          double* max_m,
                          const VisualHullRangeOptions& options = VisualHullRangeOptions(),
                          HullNearEnd* near_end = nullptr);

// A view's depth range from its masks' visual hull and COLMAP's ranges of its sparse points:
// the hull searched over [0.5 x, 2 x] the span of `all_points` and `in_mask` (the points
// observed in the view's mask; unused unless in_mask.inside_mask), then narrowed to `in_mask`
// when that lies within the hull's range (*narrowed = true): a single T group's hull is long
// along the line of sight (synthesised curly group: 0.17-1.40 m by the hull, 0.38-0.87 m with
// the points: 3.4 x finer labels). Points that reach out of the hull disagree with the masks
// and are left out: hair is hard to match, and neither range need cover it (synth_handheld
// h02: its hair at 0.35-0.62 m, its points in the mask 0.69 m away and more, COLMAP's range of
// all its points from 1.14 m). When no ray meets the hull in the search, or the hull reaches
// the search's start and the points in the mask do not overlap its range, every point may lie
// behind the head (on the room only: a head without sparse points), and the search starts 4,
// 16 and then 64 times nearer until the hull's near end lies inside it. (Points in the mask
// overlapping the hull are on the head: a close-up's cones meet in front of them, and its hull
// reaches the start.) Such a nearer range counts only where the masks, not the views'
// frusta, cut most of its rays' near ends (HullNearEnd::fraction_cut_by_masks at least 0.5),
// and the points do not narrow it. Otherwise the first search's range stands, as found
// (narrowed to the points, or none). Returns false (outputs untouched) when that gives no
// range.
enum class HullRangeSource {
  kHull,                // the hull's range
  kPointsWithinHull,    // the points in the mask, within the hull's range
  kHullInFrontOfPoints  // the hull's, searched in front of every point
};
bool HullAndPointsDepthRange(const StereoCamera& ref, const FloatMap& ref_mask,
                             const std::vector<std::pair<StereoCamera, FloatMap>>& others,
                             const DepthRange& all_points, const DepthRange& in_mask,
                             double* min_m, double* max_m, HullRangeSource* source,
                             const VisualHullRangeOptions& options = VisualHullRangeOptions());

// The range of a depth map's depths (> 0): their 1st to 99th percentile, widened by
// `margin_factor` (the near end divided by it, the far end multiplied), so that a range that
// was only known to hold the hair (HullRangeSource::kHullInFrontOfPoints: a hull that runs far
// behind the head) can be narrowed to a first estimate. False (outputs untouched) with fewer
// than `min_depths` depths.
bool DepthRangeOfEstimate(const FloatMap& depth, double margin_factor, int min_depths,
                          double* min_m, double* max_m);

}  // namespace hairmvs
