#pragma once
// Orientation-field multi-view stereo (Luo et al. 2012, Section 3; design/method.md section 2):
// one depth map per reference view of a COLMAP dense workspace, from the orientation fields of
// the reference and its source views, with structure-aware aggregation (a guided filter with the
// reference orientation field as the guide), an MRF solved coarse to fine, sub-pixel refinement
// and a final guided filter of the depth map.
//
// Outputs, in COLMAP's layout: stereo/depth_maps/<name>.photometric.bin (the first estimate)
// and <name>.geometric.bin (COLMAP's geometric pass: estimated again with the source views'
// first estimates as a prior, then filtered by consistency with them; z-depth in metres, 0 =
// invalid), stereo/normal_maps/ likewise (camera frame, facing the camera),
// stereo/confidence_maps/<name>.bin (of the map written last), and optionally coloured PNG
// pictures of depths and normals.

#include <algorithm>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "src/core/timer.h"
#include "src/mrf/mrf_solver_names.h"

namespace hairmvs {

// Which source views each reference uses (colmap_ext/source_views.h: --SourceViews.*).
struct SourceViewOptions;
// How missing orientation fields are computed (hairmvs/orientation_fields.h).
struct OrientationFieldOptions;

// What is matched between views.
enum class StereoCost {
  kOrientation,  // paper Eq. 5: -Re(O'_ref* O_v), O'_ref carried as orientation_transfer says
  // Baseline: -(zero-mean NCC of colour windows), same aggregation and MRF; a window of either
  // view without texture (colour variance at most 1e-4 of the mean square colour) counts 0.
  kPhotometric,
  // (1 - photometric_weight) x orientation + photometric_weight x photometric, each
  // aggregated as above: the two cues fail in different places (see photometric_weight).
  kCombined,
};
std::string ToString(StereoCost cost);
bool FromString(const std::string& text, StereoCost* cost);

// How an orientation of the reference is carried into a source view before it is compared
// (the orientation cost only).
enum class OrientationTransfer {
  kNone,            // compared as they are (for tests and measurements)
  kEpipoleRoll,     // paper Eq. 5: rotated by 2 (phi_ref - phi_v), one angle per view pair
  kPlaneHomography, // mapped per pixel and depth through the fronto-parallel plane's homography
};
std::string ToString(OrientationTransfer transfer);
bool FromString(const std::string& text, OrientationTransfer* transfer);

// How the depth range is sampled into labels (the paper does not say).
enum class DepthSampling { kDepth, kInverseDepth };
std::string ToString(DepthSampling sampling);
bool FromString(const std::string& text, DepthSampling* sampling);

// How the per-pixel visual hull depth bound is used (with masks).
enum class VisualHullBound {
  kOff,
  kPenalty,  // labels in front of the bound get a penalty in the data term
  kFilter,   // depths that end in front of the bound are invalid (0)
};
std::string ToString(VisualHullBound bound);
bool FromString(const std::string& text, VisualHullBound* bound);

struct OrientationStereoOptions {
  StereoCost cost = StereoCost::kOrientation;
  // The masks' folder, <mask_path>/<image name>.png as COLMAP's StereoFusion.mask_path names
  // them (empty: <workspace>/masks when it exists). The views' cached orientation fields are
  // reused only if they were computed with these masks.
  std::string mask_path;
  // Processing resolution: the longer image side is downscaled to at most this (-1: full size).
  // Depth maps are then smaller than the images, as COLMAP's are.
  int max_image_size = -1;
  // Depth range override in metres (0 or -1: ComputeDepthRange, COLMAP's rule from sparse
  // points; each on its own).
  double depth_min = -1;
  double depth_max = -1;
  // Depth range from the sparse points inside the view's mask only (COLMAP's percentile rule
  // on them), so that a background room does not widen the range; all points without a mask.
  bool depth_range_from_mask = true;
  // With masks: the depth range from the masks' visual hull (rays of the reference's masked
  // pixels carved by the other views' masks), searched over [0.5 x, 2 x] COLMAP's ranges of
  // all the view's points and of those in its mask, and narrowed to the latter when it lies
  // within the hull's (one T group's hull is long along the line of sight); the sparse rule
  // when the hull gives none.
  bool depth_range_from_visual_hull = true;
  // With masks: whatever a pixel sees lies inside every mask that sees it, so not in front of
  // where its ray enters the masks' visual hull (less the tolerance). kPenalty: labels in front
  // of the bound get the pixel's worst cost plus a slope towards the bound. kFilter: depths
  // that end in front of it are dropped. Where the data term's minimum lies in front of the
  // hull (see-through hair), the penalty pushes the depth to the next minimum, often far behind
  // (synth_straight_gantry g5_r: per-pixel median 10.4 -> 23.9 mm), while filtering drops it.
  VisualHullBound visual_hull_depth_bound = VisualHullBound::kFilter;
  // 1 / 4 mm instead of 2: the g2 group of synth_straight_gantry 4.03 / 4.02 against 4.02 mm
  // (.geometric, measured on a1ce4c7 with scripts/evaluate_stereo.sh, as the next two).
  double visual_hull_tolerance_m = 0.002;
  // The other views' masks are dilated by this many pixels before carving the hull (range and
  // bound), so that mask edges and calibration errors of a pixel or two do not carve hair.
  // 1 / 4 px: the g2 group 4.01 / 4.01 mm against 4.02.
  int visual_hull_mask_dilation_px = 2;
  // A point leaves the hull (range and bound) only when at least this many of the views that
  // see it have it outside their mask. 1: the strict hull, which one view with a wrong pose
  // or a wrong mask can carve into the hair. On synth_handheld (COLMAP's own poses, 0.3 deg
  // off) 2 changes little: .geometric 52.6 vs 51.4% complete, per-pixel median 36.95 vs
  // 38.19 mm, 3D median 1.92 vs 1.81 mm.
  int visual_hull_min_carving_views = 1;
  // depth (uniform in depth) instead: the g2 group 4.03 against 4.02 mm (measured on a1ce4c7).
  DepthSampling depth_sampling = DepthSampling::kInverseDepth;
  // Labels over the full depth range (coarse stage). 128 rather than 64, with lambda and the
  // truncation rescaled so that the smoothness per metre is unchanged: synth_straight_gantry
  // g0_c, g2_c, g4_c, g5_r per-pixel median 6.12 -> 5.87 mm; a synthesised curly T group
  // (100k strands, 960 px) 3.41 -> 2.94 mm. 256 (lambda 0.03125, truncation 16 labels: the
  // same per metre): the g2 group 4.04 against 4.02 mm (measured on a1ce4c7).
  // The MRF kernels keep about 20 bytes per label per work-item in private memory (a few
  // arrays of NUM_LABELS floats): 2.5 KB at 128 labels, 80 KB at the bound of 4096, which a GPU
  // spills to its global memory for every resident work-item (untested on a GPU: none here).
  int num_depths = 128;
  // Orientation pyramid levels used by the data term (paper: 3), finest first. The pyramid
  // itself reaches coarse_level too (PyramidLevels), whose grid the coarse stage solves on
  // whatever the data term sums (the data term keeps its scale against lambda). The coarser
  // levels see the front strands most. Measured with 1 against 3 (.geometric maps; complete /
  // per-pixel mean / median / 3D mean / 3D median, mm): synth_straight_gantry 98.7% / 7.87 /
  // 4.21 / 1.028 / 0.551 against 98.6% / 8.08 / 4.32 / 1.190 / 0.557 (inside the hair signed
  // -2.21 against -2.35 mm), 97 s; the curly demo 98.0% / 3.44 / 2.28 / 0.326 / 0.259 against
  // 98.3% / 3.46 / 2.37 / 0.302 / 0.243; but synth_handheld, whose level-0 orientation cost is
  // weakest, 93.6% / 12.57 / 6.82 / 1.661 / 0.697 against 92.2% / 10.86 / 5.41 / 1.774 / 0.632
  // (first estimates 13.2 mm). With 2: the g2 group 4.09 against 4.04 mm. The fine stage's
  // data term alone with fewer levels (a prototype on a1ce4c7, the coarse stage keeping all
  // three): level 0 only, weighted as 1.5 / 3 times its source weights, or levels 0 and 1: the
  // g2 group 4.00 / 4.01 / 4.01 mm against 4.02 (smooth part over 31 px 2.97 / 2.99 / 3.00
  // against 3.03 mm; evaluate_depth). Level 0 alone where the hair is dense and all three
  // levels where it thins out (measured on c5d4290 as an upper bound, not kept: the g2 group's
  // .geometric maps of both runs merged per pixel by the mask's hair fraction in a 15 x 15 /
  // 31 x 31 px window, >= 0.5 / 0.8 / 0.95 taking num_levels 1): 3.87-3.89 mm against 3.89
  // (num_levels 1) and 4.02 (3); the silhouette band 6.02-6.21 mm against 6.21 and 5.89.
  int num_levels = 3;
  // Level 0's share of each source's orientation cost, by how far the source looks away from
  // the reference: (level0_weight_angle_deg / angle)^level0_weight_angle_power, clamped to
  // [1/4, 4], against 1 for every coarser level, the levels' weights then scaled to average 1
  // (so that each source's cost keeps its scale against lambda). Individual strands, which
  // level 0 resolves, match across narrow pairs, but across wide ones their occlusions and
  // turns change while the coarser levels' bands of strands still agree. 0: every level
  // alike, as the paper. Measured (.geometric maps; complete / per-pixel mean / median / 3D
  // mean / 3D median, mm), 20 degrees and power 2 against equal levels: synth_straight_gantry
  // (10 and 20 degree pairs) 98.7% / 7.93 / 4.17 / 1.066 / 0.526 against 98.6% / 8.09 / 4.24 /
  // 1.122 / 0.526; synth_handheld (6-34 degree pairs) 93.3% / 9.82 / 4.70 / 1.218 / 0.567
  // against 93.3% / 9.91 / 4.78 / 1.304 / 0.588; the curly demo group 98.2% / 3.46 / 2.31 /
  // 0.289 / 0.241 against 97.8% / 3.70 / 2.45 / 0.289 / 0.229; but a set of wide pairs only
  // (`hairmvs synthesize --style curly --rig handheld --num_views 12 --width 800 --seed 7`,
  // sources 26-89 degrees away) trades: 93.8% / 5.09 / 2.86 / 0.379 / 0.306 against 95.0% /
  // 4.99 / 2.83 / 0.408 / 0.336. Power 1: the gantry 98.6% / 7.96 / 4.19 / 1.091 / 0.527,
  // synth_handheld 93.7% / 9.89 / 4.72 / 1.287 / 0.574, the curly demo group 2.37 mm, the
  // wide set 94.0% / 5.06 / 2.84 / 0.383 / 0.308; 30 degrees (power 1): the g2 group 4.01 mm
  // (equal levels 4.07), synth_handheld 4.75 mm. One weight for all sources does not do it:
  // level 0 x 2 / x 0.5 gives the g2 group 4.01 / 4.16 mm but synth_handheld 4.87 / 4.68 mm.
  double level0_weight_angle_deg = 20;
  double level0_weight_angle_power = 2;
  // Match each source's pyramid level to the scale at which it images the hair: the reference's
  // level l meets the source's level l + round(log2(ratio)) (SourceLevelOffset), clamped to
  // the source's levels. The filter bank's bands are in pixels, so a source imaging the hair at
  // twice the scale sees other strands' bands at the same level. 0: level l meets level l.
  // Measured in the README (a T group of mixed sizes, synth_handheld). Prototypes, not kept: a
  // source dropped at the levels where its matching level is clamped did worse there; a source
  // between two levels (log2(ratio) at least 0.2 from a whole number) matched at both, weighted
  // by its nearness to each, gave the README's wide handheld set 91.5% / 4.78 / 2.80 / 0.399 /
  // 0.319 against 91.3% / 4.76 / 2.81 / 0.405 / 0.319 at the nearer level alone.
  bool match_source_scale = true;
  // Guided-filter windows (paper: 7, 11, 15 px; it does not say which level gets which) per
  // level 0 (finest), 1, 2. 15/11/7 measured better than 7/11/15 on synth_straight_gantry g0_c
  // (per-pixel median 12.2 vs 14.8 mm). With both passes they hardly matter: the g2 group's
  // .geometric median 4.04 mm at 15/11/7, 4.04 at 9/7/5, 4.05 at 11/9/7, 4.06 at 21/15/11.
  // A window along the strand instead of a square one (a prototype on 4f80f5d, not kept: the
  // mean over the same length along a line through the pixel in its field's direction, 1 or 3
  // px wide, so that a strand's costs are not mixed with those of the strands beside it, which
  // may lie in another layer): at level 0, 1 / 3 px wide, or at every level, 3 px wide: the g2
  // group 4.01 / 4.02 / 4.01 mm against 4.02, the interior's lean -2.06 / -2.09 / -2.08 mm
  // against -2.14, although the data term alone moved from 4.56 mm, 1.13 mm in front, to 6.82
  // / 5.99 / 7.15 mm, 0.97 / 0.21 / 1.44 mm behind. With lambda 0.02 instead of 0.125 the
  // interior still leans -2.02 mm (square windows) and -1.94 (along the strand, level 0).
  // (The data term alone is the coarse stage's cheapest label per coarse pixel; on the coarse
  // pixels that are all hair, `evaluate_data_term --min_hair_fraction 1`, -1.59 mm with square
  // windows and +0.26 mm along the strand at level 0, at a median error of 4.43 / 6.83 mm.)
  // The background in a window costs 0 at every label, so near the silhouettes the aggregated
  // data term is weaker against the smoothness and the prior. Each level's aggregated cost
  // divided by the same filter's response to the hair indicator (floored at 0.1 / 0.3; a
  // prototype on af0af88, not kept) did not help: the g2 group 98.6% / 6.17 / 4.07 mm and
  // 99.0% / 6.15 / 4.05 mm against 99.6% / 6.07 / 4.02, the silhouette band 6.09 / 5.98 mm
  // against 5.89, the interior 2.96 mm either way. Nor did shiftable windows (a prototype at
  // stop 56, after the guided filter each slice's minimum over the windows within r px: the
  // cheapest window that still holds the pixel, so that a window on two layers may move onto
  // one, the classic remedy for windows that straddle a depth step): r = half / all of the
  // window's radius, the g2 group 99.1% / 6.20 / 4.08 and 98.5% / 6.32 / 4.17 mm against 99.6%
  // / 6.07 / 4.02, the interior's lean -2.20 / -2.29 mm against -2.14: the cheapest window
  // favours the front layer's continuous strands further.
  int window_px_level0 = 15;
  int window_px_level1 = 11;
  int window_px_level2 = 7;
  // Guided filter regulariser (paper Eq. 8: eps = 0.12).
  double guided_filter_eps = 0.12;
  // The reference orientation field is scaled to this RMS magnitude (over its non-zero
  // pixels) where it guides the aggregation (eps) and weighs the smoothness (sigma_o), whose
  // constants are in units of |O|^2 and |O|: |O| = F^gamma depends on the image's intensity
  // scale, which the paper does not give. 0: the field as computed from intensities in [0, 1],
  // an RMS of about 0.09 (synth_straight_gantry g2_c: median |O|^2 0.0065), at which the
  // paper's eps and sigma_o make the guided filter nearly a box filter and the smoothness
  // nearly uniform (median w_s 0.96). Stronger, structure-aware weights do not help here
  // (.geometric per-pixel median; 0 / 0.001 = uniform / 0.2 / 0.3 / 0.5 / 1 ~ 8-bit
  // intensities): synth_straight_gantry g2 group 4.16 / 4.16 / 4.11 / 4.08 / 4.14 / 4.19 mm
  // (99.1 / 99.3 / 99.1 / 98.6 / 97.7 / 95.0% of the hair); the curly demo group with 0.3 / 1:
  // 2.61 / 2.70 vs 2.39 mm (mean 4.70 / 5.26 vs 3.59); synth_handheld h01, h05, h10, h15 first
  // estimates, 0.3 / 1: 35.19 / 46.12 vs 36.27 mm. Decoupled along orientation changes, curls
  // and see-through silhouettes fall onto the hair behind.
  double guide_rms = 0;
  // Smoothness weight w_s = exp(-|O(p) - O(p')|^2 / (2 sigma_o^2)) (paper Eq. 3: 0.15).
  // The same for both neighbours of a pixel, whatever the strand's direction. Weighted by it
  // instead (a prototype on 72fbefd, not kept: w_s times 1 + b cos 2(Theta - the edge's
  // direction), Theta of the pair's summed field, so that the depth is smoother along a
  // strand than across strands that may lie in different layers), b = 0.5 / 0.9 / -0.5:
  // the g2 group 4.05 / 4.06 / 4.07 mm against 4.02 (the interior 2.98 / 2.98 / 2.99 against
  // 2.96, the silhouette band 5.96 / 6.01 / 6.01 against 5.89).
  double sigma_o = 0.15;
  // lambda of E = E_d + lambda E_s, per squared coarse label (not given in the paper), for
  // labels lambda_label_step_px apart (below: each view's is scaled to its own). With
  // the normalised fields, on synth_straight_gantry g0_c + g0_l: 0.02 / 0.1 / 0.5 / 2 gave
  // per-pixel medians of 9.1 / 7.2 / 6.1 / 6.4 mm. (With the raw fields, whose costs are about
  // 100x smaller, 0.002 was best: 0.0005 / 0.002 / 0.008 / 0.05 gave 38 / 15 / 32 / 56 mm.)
  // Measured with 64 labels (lambda 0.5 there; 0.125 with 128 labels is the same per metre).
  // With both passes, the g2 group's .geometric median 4.04 mm with 0.125, 4.06 with 0.05.
  // The coarse and fine stages share it, though a coarse pixel's edge spans 4 level-0 pixels
  // (per unit area the coarse smoothness weighs about 16 times more against the data term).
  // The coarse stage's lambda scaled apart (a prototype at stop 57), x 0.25 / x 4: the g2 group
  // 98.6% / 4.15 mm and 99.6% / 4.10 mm against 99.6% / 4.02 mm.
  // Its unit is the label, uniform in inverse depth by default (depth_sampling): per squared
  // millimetre the smoothness charges near depths more than far ones ((z_far / z_near)^4).
  double lambda = 0.125;
  // The labels' disparity step at which lambda is given (LabelStepPxPerRadian in
  // src/stereo/stereo_geometry.h: px per label for a source one radian away, the focal length
  // times the labels' relative depth step in the middle of the range); each view's lambda is
  // scaled by (its step / this)^2 (0: lambda as given, per label). The data term sees the
  // surface at the image's scale, the smoothness in labels: on an image a third the size the
  // same surface's labels change three times faster per pixel, so that a constant lambda
  // charges its slope 9 times more against the data term (per view, the data term scales with
  // the pixels, the squared label step per pixel with 1 / pixels), and flattened the hair far
  // behind it. Measured on a synthesised straight T group (`hairmvs synthesize --num_groups 1
  // --width W`, .geometric, per-pixel median; lambda unscaled): W = 320: 35.99 mm with 0.125,
  // 0.007 / 0.0139 / 0.03 / 0.06: 3.99 / 4.16 / 4.77 / 9.26 mm; W = 480: 4.62 mm with 0.125,
  // 0.015 / 0.031 / 0.06: 3.17 / 3.27 / 3.17 mm; W = 960: 2.82 mm with 0.125, 0.5: 2.81 mm.
  // The optimum falls with the square of the size. 4 px: the steps of the 960 px gantry's
  // views (3.4-4.4 px; synth_handheld's 800 px views 2.3-4.1), where 0.125 was chosen. Scaled
  // (the views' lambda 0.014 at 320 px, 0.53 at 1920): W = 320 / 480 / 960 / 1920: 4.19 /
  // 3.24 / 2.81 / 2.60 mm against 35.99 / 4.62 / 2.82 / 2.78 unscaled; synth_straight_gantry
  // 98.6% / 7.92 / 4.17 mm against 98.7% / 7.93 / 4.17, synth_handheld 92.6% / 9.89 / 4.73 mm
  // against 93.0% / 9.79 / 4.69 (its lambda 0.04-0.13).
  // The sources' baselines are left out: a wider one steps more disparity per label, but its
  // match is no sharper per label (on the 320 px group, g0_l and g0_r, whose sources reach 20
  // degrees, flattened with 0.125 while g0_c, whose sources are 10 degrees away, did not).
  // truncation_labels stays in labels (a depth jump between layers, not a slope): with more
  // labels it is rescaled by hand as before.
  double lambda_label_step_px = 4.0;
  // Truncation of the squared label difference of the smoothness term, in coarse labels
  // (<= 0: plain quadratic, as the paper). 8 coarse labels of 128: 4 of 64. 3: the g2 group's
  // .geometric median 4.04 -> 4.25 mm, 99.7 -> 97.6% covered. A quadratic term prefers a ramp
  // to a step (steps between hair layers come out as ramps); a truncated linear one, which
  // charges both alike (a prototype of the path minimum and ICM, not kept), did worse on the
  // g2 group with lambda 0.125 / 0.25 / 0.5 / 1 / 2 per coarse label: 4.23 / 4.16 / 4.10 /
  // 4.19 / 4.62 mm, the silhouette bands pushed behind the hair (signed +1.9 to +3.8 mm).
  double truncation_labels = 8;
  // MRF solver, by name (graph_cuts, semi_global, ... as src/mrf offers). semi_global: graph
  // cuts took 445 s for the coarse stage of a 960 x 640 view (128 labels), semi-global 118 s.
  // Today's pipeline, the g2 group of synth_straight_gantry (.geometric, both passes): semi_global
  // 99.7% / 4.04 mm median in 10 s, graph_cuts 99.6% / 4.08 mm in 64 s, belief_propagation
  // 98.1% / 4.11 mm in 44 s: the solver is not what limits the accuracy.
  std::string mrf_solver = "semi_global";
  int mrf_max_cycles = 3;
  // ICM sweeps that polish the semi-global (or belief-propagation, graph-cut) labels; each
  // lowers the energy, none changes a label that is already a local optimum. They hardly change
  // the maps here: 10 / 3 / 0 on synth_straight_gantry g2 (first estimates) per-pixel median
  // 4.31 / 4.31 / 4.34 mm; the curly demo group 10 / 3 / 0: 2.36 / 2.37 / 2.36 mm; a 4-view
  // set at 1404 x 936, 10 / 3: 6.10 / 6.11 mm and MRF 23.3 / 19.2 s of 67-70 s.
  int mrf_icm_polish_iterations = 10;
  // Coarse to fine: the full label range is solved on the grid of this orientation level, then
  // a band of fine labels around the upsampled coarse depth at full resolution. -1: single stage
  // (full range at full resolution). Level 1 (a grid twice as fine, so that the coarse
  // smoothness charges a steep rim less per pixel) measured worse on the g2 group of
  // synth_straight_gantry (2447a0e, .geometric): 99.4% / 6.25 / 4.08 mm in 43 s against 99.6% /
  // 6.07 / 4.02 mm in 35 s, the silhouette band 5.89 -> 6.03 mm. Single stage (-1: every
  // label at full size, the windows' slices the hull-based labels, not a coarse estimate's
  // surface) worse as well (stop 57): 98.9% / 6.43 / 4.15 mm, the interior still 2.13 mm in
  // front, the silhouette band 6.27 mm; the band around a coarse estimate is not what leans.
  int coarse_level = 2;
  // The finest pyramid level in the coarse stage's data term (0: all levels, as the fine stage);
  // the levels used count for the ones left out. The all-label cost volume of level 0 is most
  // of the coarse stage's work: 1 on a synthesised 4-view set at 1404 x 936 takes the time per
  // finished view from 17.3 to 13.1 s, but the per-pixel median from 6.10 to 7.27 mm (90.9 ->
  // 89.0% complete).
  int coarse_first_level = 0;
  // With masks: the coarse stage's num_depths labels start, at each pixel, at the visual
  // hull's depth bound (where its ray enters the hull, less visual_hull_tolerance_m) and run as
  // far behind it as the range's labels are long, rather than spanning the range from its
  // front. The aggregation windows (and the photometric cost's NCC windows) then gather costs
  // at one depth behind the hull's surface, which leans as the hair does, rather than at one
  // depth in front of the camera: on hair turning away from the view, a fronto-parallel window
  // mixes depths centimetres apart. The smoothness stays on depths. Measured (.geometric maps,
  // with strand_plane_from_visual_hull): synth_handheld 60.2 -> 74.5% of the hair, per-pixel
  // median 6.22 -> 5.85 mm, mean 13.31 -> 11.67, 3D mean 3.17 -> 2.62 mm; synth_straight_gantry
  // g2 group 4.22 -> 4.03 mm; the curly demo group 2.36 -> 2.35 mm (its one T group's hull is
  // long: the labels reach the hair all the same).
  // Outside the reference's mask, where the hull has no bound, the labels count from the
  // range's front (VisualHullLabelBase: base 0), so that there the hair's costs, which the
  // aggregation carries beside the mask, read as depths far in front of the hair. Counting them
  // from the nearest pixel's bound instead (found by a review at stop 55, measured on 0e931bc
  // and reverted; scripts/evaluate_stereo.sh, complete / per-pixel mean / median / 3D mean /
  // 3D median, base 0 -> nearest bound): a strand sphere whose field stops at the mask (a test
  // of 0e931bc) 60.5% of the hair within 3 px of the mask's edge with a depth at 73 mm -> 100%
  // at 8 mm, but synth_straight_gantry 98.7% / 7.93 / 4.17 / 1.018 / 0.524 -> 98.7% / 7.87 /
  // 4.16 / 0.982 / 0.516, synth_handheld 93.0% / 9.78 / 4.69 / 1.169 / 0.550 -> 92.7% / 9.90 /
  // 4.75 / 1.289 / 0.546, the curly demo group 98.2% / 3.46 / 2.31 / 0.289 / 0.241 -> 98.6% /
  // 3.61 / 2.35 / 0.277 / 0.236 (its silhouette band 4.40 -> 4.68 mm, signed +2.08 -> +2.93:
  // the front pull had offset part of the silhouettes' lean behind), and the colour cost on
  // synth_handheld 87.1% / 13.46 / 5.60 -> 83.9% / 17.41 / 6.30 mm (its data term alone 15.19
  // -> 19.35 mm, signed +8.2 -> +14.9): the colour cost, unlike the orientation cost (whose
  // field is 0 outside the mask), costs the background too, and with consistent labels the
  // room behind the hair, matched at its own depth, pulls the hair's edge behind. Masking the
  // colour cost as the orientation cost is (a prototype at stop 56: each level's colour cost
  // set to 0 where the reference's field is 0, before the aggregation) does not change that:
  // synth_handheld's colour cost with base 0, masked, 86.6% / 13.41 / 5.61 / 1.943 / 0.560
  // (unmasked 87.1% / 13.46 / 5.60 / 2.018 / 0.563), with the nearest bound, masked, 84.4% /
  // 17.28 / 6.35 / 2.484 / 0.566, its data term alone 19.65 mm, signed +15.3: the background
  // lies inside the NCC windows of the hair's edge pixels themselves, not only beside them.
  bool coarse_labels_from_visual_hull = true;
  // With coarse_labels_from_visual_hull: the coarse stage's smoothness compares how far behind
  // the hull's bound neighbouring pixels lie (a surface parallel to the hull's costs nothing)
  // instead of their depths (a fronto-parallel one costs nothing). Off by default: it helps
  // where the hull is tight and the hair leans, and misleads where the hull is loose.
  // Measured (.geometric maps, off -> on): synth_handheld (20 views around) 74.5 -> 78.4% of
  // the hair, per-pixel median 5.85 -> 5.27 mm, mean 11.67 -> 9.55, 3D mean 2.68 -> 1.48 mm;
  // synth_straight_gantry (32 views) 98.4 -> 95.8%, 4.55 -> 4.49 mm, mean 9.66 -> 8.75, 3D mean
  // 1.48 -> 1.78 mm (a trade); the curly demo group (one T group: its hull is long along the
  // line of sight) 97.9 -> 76.2%, 2.35 -> 4.13 mm. Again on 24e7342 (complete / per-pixel
  // median / 3D median): synth_handheld 93.3% / 4.78 / 0.588 -> 89.4% / 4.55 / 0.585 mm, below
  // the 90% of the hair that the maps must cover; synth_straight_gantry 98.6% / 4.24 / 0.526 ->
  // 96.8% / 4.27 / 0.537 mm.
  bool coarse_smoothness_along_visual_hull = false;
  // The fine stage's band: fine_num_labels labels fine_label_step coarse labels apart, centred
  // on the upsampled coarse depth. A band's slice is a constant offset from that surface, not a
  // constant depth, so the aggregation's windows sum costs along the coarse surface (slanted
  // with it, its errors too), as they follow the hull with coarse_labels_from_visual_hull.
  // Neither its reach nor its step limits the accuracy here
  // (.geometric maps, synth_straight_gantry g2 group, 2.05 mm coarse labels; default 99.7% /
  // per-pixel median 4.04 mm / 3D median 0.522 mm): step 0.25 (band +-2 coarse labels) 4.07 /
  // 0.541, step 0.25 with 32 labels 4.04 / 0.529, step 1 (+-8) 4.03 / 0.519; 32 labels of 0.5
  // 4.02 mm. The error left is a smooth one (the g2_c map's error, median-filtered over 31 x 31
  // px: 2.85 mm), not the labels' quantisation. Nor is it the MRF's: the band's cheapest label
  // per pixel (its aggregated data term and prior, no smoothness) lies within 1-2 fine labels
  // of the MRF's label at the 10th and 90th percentiles, and the MRF's label moved by the
  // median of that difference over 15 x 15 px (a prototype on ef551e6) gives the g2 group 4.02
  // mm as before (4.01 with level 0 aggregated along the strand, 4.05 with every level so).
  int fine_num_labels = 16;
  double fine_label_step = 0.5;  // in coarse labels
  // Depth slices per kernel launch (memory vs launch overhead).
  int slice_block = 8;
  // Sub-pixel refinement (paper Eq. 9) and the final guided filter of the depth map (Eq. 10).
  // Without the filter the g2 group's .geometric median goes 4.04 -> 4.14 mm. Filtering within
  // the mask only (a prototype, measured on 69876ad: the depth times the mask and the mask
  // filtered, then divided, where the filtered mask exceeds 0.2 / 0.5, so that the background's
  // depths do not reach the silhouette's) did not help: the g2 group 99.7% / 6.10 / 4.04 mm
  // either way against 99.6% / 6.07 / 4.02, the silhouette band 5.89 -> 5.93 / 5.92 mm.
  bool subpixel_refinement = true;
  bool final_guided_filter = true;
  // Pixels whose confidence (aggregated cost margin of the chosen coarse label over the best
  // label at least 2 labels away, clamped at 0) is below this get depth 0 (0: keep all).
  double min_confidence = 0.0;
  // Pixels whose label is at either end of the range are outside it: depth 0.
  bool filter_range_ends = true;
  // How a reference orientation is carried into a source view (orientation cost). The paper's
  // epipole roll correction exp(2i(phi_ref - phi_v)) (Eq. 5) rotates every orientation by one
  // angle per view pair, which is exact only where the views differ by a roll about their
  // baseline. plane_homography maps the strand direction at each pixel and depth hypothesis
  // through the homography of the fronto-parallel plane at that depth (the strand assumed to
  // lie in it): per-pixel, it follows perspective and elevation changes between wide-baseline
  // views, and agrees with the roll where the views are close. Measured (.geometric maps,
  // epipole_roll -> plane_homography): synth_handheld, 20 views: per-pixel median 8.62 -> 7.19
  // mm (mean 23.96 -> 17.81, 3D mean 6.35 -> 4.27 mm), 58.7 -> 57.6% of the hair; first
  // estimates 29.12 -> 16.74 mm; synth_straight_gantry, 32 views (10 degree baselines): the
  // same (4.73 mm, 97.4%, 3D median 0.573 -> 0.577 mm); the curly demo group 2.39 -> 2.39 mm.
  // With normalised fields (orientation_normalization_radius_px > 0) the phase carried is the
  // normalised field's, the pixel's deviation from its window's mean, which is no strand's
  // direction; the homography is not a rotation, so carrying it differs from turning the
  // normalised field by the angle the raw strand turns by. That alternative (a prototype,
  // measured at stop 57, tested against the CPU reference: the raw field's phase carried and
  // the normalised field turned with it) did not help: synth_handheld 93.0% / 9.79 / 4.69 /
  // 1.183 / 0.558 mm -> 92.8% / 9.73 / 4.69 / 1.196 / 0.551 (first estimates 6.97 -> 7.30 mm,
  // the data term alone 10.88 -> 11.67 mm), synth_straight_gantry 98.7% / 7.93 / 4.17 / 1.024 /
  // 0.527 -> 98.7% / 7.99 / 4.18 / 1.034 / 0.523 (complete / mean / median / 3D mean / 3D median).
  OrientationTransfer orientation_transfer = OrientationTransfer::kPlaneHomography;
  // The plane a strand is taken to lie in by plane_homography. With masks: parallel to the
  // masks' visual hull where the pixel's ray enters it (hair is what makes the silhouettes, so
  // the hull's surface leans as the hair's does, though it lies a little in front of it;
  // LogDepthGradient in src/stereo/stereo_geometry.h), fronto-parallel where the ray misses the
  // hull; without masks always fronto-parallel. A strand on the side of the head, seen from a
  // view 30 degrees away, turns differently in the source than one facing the camera.
  // Tilts beyond max_strand_plane_tilt_deg (the hull's walls at the silhouettes) are clamped.
  // Measured (.geometric maps, fronto-parallel -> visual hull): synth_handheld (20 views)
  // 57.8 -> 60.1% of the hair, per-pixel median 7.14 -> 6.20 mm, mean 18.30 -> 13.31, 3D median
  // 0.869 -> 0.789 mm; first estimates 16.75 -> 12.29 mm; synth_straight_gantry g2 group 4.18
  // -> 4.22 mm, g5 group 5.96 -> 5.91; the curly demo group 2.39 -> 2.36 mm.
  bool strand_plane_from_visual_hull = true;
  // 60 / 80 degrees: the g2 group 4.02 / 4.04 mm against 4.02.
  double max_strand_plane_tilt_deg = 70;
  // Orientation cost: match locally normalised orientation fields, (O - mean) / std over a
  // (2 r + 1)^2 window at every level (0 = the paper's raw fields). Default 3: on
  // synth_straight_gantry g0_c it took the winner-take-all median error from 47 to 8 mm. See
  // NormalizeOrientationField in src/stereo/depth_estimator.h for why.
  int orientation_normalization_radius_px = 3;
  // Added to the local variance of the normalisation, as a fraction of the field's mean |O|^2
  // over its non-zero pixels (> 0), so that it damps the same windows whatever the confidence's
  // exponent and the photos' contrast. Until stop 22 it was absolute, 1e-3: about a tenth of
  // the renders' mean |O|^2 (0.008 gantry, 0.012 handheld) with confidence_gamma 0.5, but ten
  // times the mean with confidence_gamma 1, where it swamped the variance and the depths failed
  // (g2_c alone, the T group's sources, no geometric pass: 27.5 mm; relative 0.1: 4.06).
  // Measured (.geometric, per-pixel median): relative 0.1 synth_straight_gantry 98.6% / 4.32
  // mm, synth_handheld 92.0% / 5.38 mm (absolute 1e-3: 98.6% / 4.32, 92.2% / 5.41); absolute
  // 1e-2 97.7% / 4.40 and 87.7% / 5.89 mm.
  double orientation_normalization_eps = 0.1;
  // Photometric and combined costs: NCC window (px, odd) at every level.
  int ncc_window_px = 7;
  // Combined cost only: the photometric cost's share of the data term, the orientation cost
  // having the rest (both are sums over the source views of terms in [-1, 1], so equal shares
  // weigh them alike). Measured (equal shares, against the orientation cost alone): the data
  // term alone, median error of its best label, synth_handheld 16.34 -> 10.47 mm (photometric
  // alone 12.31), synth_straight_gantry 4.89 -> 4.35 mm, the curly demo group 5.32 -> 3.05 mm;
  // the .geometric maps' median 5.85 -> 5.30 (both with 4 source views: with 6, the default,
  // colour matching loses on the handheld's wider pairs: 5.75 -> 5.67 mm), 4.55 -> 4.32,
  // 2.35 -> 2.24 mm. About 4 x the time (a 1404 x 936 T group: 62 -> 263 s): the colour cost
  // reads every pixel, the orientation cost only the masks' hair. Hence not the default.
  double photometric_weight = 0.5;
  // Occlusions (Kang, Szeliski and Chai 2001, "Handling occlusions in dense multi-view
  // stereo"): at each pixel and depth the data term sums, per cost, only the
  // ceil(best_source_fraction x N) of its N sources whose aggregated cost is lowest (scaled by
  // N / that count, so that the cost keeps its scale against lambda), so that a point hidden
  // from some sources (hair behind the front strands, seen through gaps that move between views)
  // is judged by the sources that see it. 1 = every source (the paper's Eq. 4). Each source is
  // then aggregated on its own: the aggregation's time times N. Measured (0.5: 2 of a T
  // group's 3 sources, 3 of 6), against 1: synth_straight_gantry .geometric 98.8 -> 98.6%
  // covered, median 4.58 -> 4.47 mm, mean 9.89 -> 9.65, 3D median 0.575 -> 0.559 mm, the
  // depths' layer 27 -> 29%, 161 -> 295 s; synth_handheld 93.4 -> 92.8%, 5.61 -> 5.57 mm, 3D
  // median 0.647 -> 0.658 mm, 117 -> 262 s (0.67, 4 of 6: 92.9%, 5.51 mm, 3D median 0.655 mm,
  // 252 s); the curly demo 2.37 -> 2.38 mm. Hence not the default. Selecting in the fine band
  // only (the coarse stage summing every source) keeps less of the gain for less time: the
  // gantry 4.51 mm in 218 s, the handheld 5.62 mm in 179 s. (These before the geometric pass
  // read the views looking the same way and the crop; with both, 0.5: the gantry 98.6 ->
  // 98.5%, 4.32 -> 4.23 mm, 3D median 0.560 -> 0.541 mm, 128 -> 198 s; the handheld 92.2 ->
  // 91.6%, 5.40 -> 5.44 mm, 75 -> 156 s.)
  double best_source_fraction = 1.0;
  // Geometric consistency, as COLMAP's patch_match_stereo names its passes: each view's depth
  // map as first estimated is written as depth_maps/<name>.photometric.bin. The geometric pass
  // then estimates each view again with its source views' .photometric maps (and those of the
  // views looking the same way, geom_consistency_max_view_angle_deg) as a prior (COLMAP's
  // geometric pass; GeometricPrior in src/stereo/geometric_prior.h) and keeps the
  // pixels that at least geom_consistency_min_views of those maps agree with (forward-backward
  // reprojection error within geom_consistency_max_error_px, COLMAP's
  // filter_geom_consistency_max_cost; src/stereo/consistency_filter.h) as .geometric.bin.
  // Sources without a .photometric map yet (a job array's other jobs) are skipped; run again
  // with geom_consistency_only once all jobs are done. Off: the estimate is written as
  // single_pass_type.
  bool geom_consistency = true;
  // The name of the maps of a run without geom_consistency: "geometric" (what colmap
  // stereo_fusion's default --input_type reads) or "photometric" (what colmap
  // patch_match_stereo writes without its geometric pass, and so `hairmvs patch_match_stereo
  // --PatchMatchStereo.geom_consistency 0` too).
  std::string single_pass_type = "geometric";
  double geom_consistency_max_error_px = 4.0;
  int geom_consistency_min_views = 1;
  // A view whose ray to a depth's point meets the reference's at less than this does not count
  // as agreeing (COLMAP's filter_min_triangulation_angle, its default): beside the reference,
  // it reprojects any depth onto the pixel. The views looking the same way are chosen by their
  // direction alone and may sit there (video frames).
  double geom_consistency_min_triangulation_angle_deg = 3.0;
  // 4 px rather than COLMAP's 1: the hair's own depth texture is a few pixels of disparity
  // deep. Measured without the prior (filter only), kept hair pixels / per-pixel median for
  // 3 / 4 / 5 px: synthesised curly T group (defaults, seed 1) 90.7 / 92.3 / 93.5% at
  // 2.33 / 2.37 / 2.41 mm; seed 2 91.9 / 93.5 / 94.6% at 2.40 / 2.44 / 2.48 mm;
  // synth_straight_gantry 86.1 / 88.2 / 89.6% at 4.52 / 4.63 / 4.71 mm.
  // The prior's weight, relative to the data term's median range over the coarse labels (0:
  // no second estimation, the .photometric map is only filtered), and the reprojection error
  // (px) at which a depth costs the most (COLMAP's geom_consistency_max_cost: 3). Weight 0 /
  // 0.5 / 1 / 2 on synth_straight_gantry groups 3 and 5 (8 views): kept 84.5 / 90.5 / 93.3 /
  // 95.1% of the hair pixels at a per-pixel median of 4.79 / 4.80 / 4.82 / 4.89 mm; the
  // synthesised curly T group (seed 1), 0 / 1: 92.3 / 96.7% at 2.37 / 2.36 mm (mean 3.90 /
  // 3.71). Every view is estimated twice; with the coarse volumes kept between the estimates
  // the geometric pass takes under half as long as the first (32 gantry views: 143.2 s, then
  // 69.8 s). The error at which the prior stops pulling: 6 px, wider than the filter's
  // tolerance (geom_consistency_max_error_px, 4), so that a depth the filter would drop is
  // still pulled towards the depths its sources agree on, rather than COLMAP's 3, inside it.
  // Measured (.geometric maps, 3 / 6 / 8 / 10 px): synth_handheld (3 rounds) 84.9 / 88.3 /
  // 89.4 / 90.0% of the hair at a per-pixel median of 5.47 / 5.56 / 5.65 / 5.73 mm (3D median
  // 0.633 / 0.655 / 0.669 / 0.679 mm); on the pixels both 3 and 6 px keep (83.0% of the hair)
  // 5.36 and 5.36 mm, with 10 px 5.34 / 5.44 mm: the depths added (5.3% of the hair at 6 px,
  // median 11.1 mm) are harder ones, those kept are no worse. The g2 group 99.6 -> 99.7% at
  // 4.03 -> 4.04 mm, the curly demo 97.9 -> 98.0% at 2.35 -> 2.36 mm (3 -> 6 px).
  // With the 6 px reach and the rounds, weight 1 / 2 / 4: synth_handheld 88.3 / 93.4 / 94.6%
  // of the hair at 5.56 / 5.61 / 5.79 mm (3D median 0.655 / 0.641 / 0.649 mm, mean 10.97 /
  // 11.39 / 11.70), and on the pixels both keep 5.48 / 5.33 (1 / 2) and 5.51 / 5.60 (2 / 4):
  // 2 is more accurate where 1 keeps a depth as well, 4 less; synth_straight_gantry (1 / 2)
  // 98.5 / 98.8% at 4.57 / 4.58 mm (4.56 / 4.55 on the pixels both keep; the 0.5% added are
  // 38 mm off, so the mean goes 9.74 -> 9.89 and the 3D mean 1.53 -> 1.59 mm); the g2 group
  // 4.04 / 4.03 mm, the curly demo 98.0 / 98.3% at 2.36 / 2.37 mm.
  // Near the silhouettes, where a view's own data term sees through the fringe and a view of
  // another T group sees the same hair face on, the prior's weight times 1 + b within d px of
  // the background (a prototype on 5014a50, not kept; groups 3 to 6 of synth_straight_gantry,
  // 16 views, 97.5% / 11.46 / 4.67 mm with the defaults): b = 2 / 8 / 8 / 50 at d = 20 / 20 /
  // 40 / 60: 4.65 / 4.65 / 4.62 / 4.63 mm, the silhouette band 8.88 -> 8.82 / 8.81 / 8.67 /
  // 8.66 mm: the other views' maps see through the same fringe.
  double geom_prior_weight = 2.0;
  double geom_prior_max_error_px = 6.0;
  // Rounds of the geometric pass (with geom_prior_weight > 0), at most
  // geom_consistency_iterations: each round estimates every view again with its sources' maps
  // of the previous round as the prior (the .photometric maps in the first), and the last
  // round's maps are filtered by consistency with the maps their prior came from. A view whose
  // first estimate went wrong (synth_handheld h01: 49 mm behind the hair, put right by the first
  // round's prior) gives its neighbours a wrong prior in the first round and a corrected one in
  // the second. Measured (.geometric maps, 1 / 2 / 3 rounds): synth_handheld (views all
  // around) 80.3 / 84.2 / 84.9% of the hair, per-pixel median 5.75 / 5.59 / 5.47 mm, mean 11.28
  // / 10.97 / 10.82, 3D mean 2.13 / 1.84 / 1.82 mm, in 115 / 154 / 167 s; synth_straight_gantry
  // (T groups) 98.4 / 98.7 / 98.7%, 4.55 mm each, mean 9.70 / 9.88 / 9.91, 3D mean 1.51 / 1.55
  // / 1.51 mm, in 221 / 273 / 325 s; the curly demo group 2.35 / 2.36 mm (1 / 2). A round
  // costs a third of a first estimate (a 1404 x 936 T group: 15.5 -> 20.8 s per map with two)
  // and helps only where the views disagree, so a round after the first runs only while (a)
  // at least geom_consistency_min_inconsistent_fraction of the previous round's depths are
  // inconsistent with the maps their prior came from (the filter's test) and (b) from the
  // third round on, the previous round raised the consistent fraction by at least
  // geom_consistency_min_gain. The consistent fractions after rounds 1 / 2 / 3 (all views'
  // depths, hair and head): synth_handheld 76.7 / 80.8 / 81.6%, so 3 rounds; the gantry 97.6%,
  // a synthesised 1404 x 936 curly T group 97.9%, the curly demo 97.9%: 1 round (all figures
  // here with geom_prior_max_error_px 3 and weight 1; with 6 px and weight 2, synth_handheld
  // 85.3 / 89.7% after rounds 1 / 2, 3 rounds, 93.4% of the hair at 5.61 mm; the gantry 98.1%,
  // 1 round). Exactly N rounds: min_inconsistent_fraction 0 and min_gain -1. Later rounds
  // need every view's previous round, which only one process has: a job of an array takes its
  // other views' .photometric maps in every round, and decides on its rounds from its own
  // views.
  int geom_consistency_iterations = 3;
  // The geometric pass (prior and filter) reads, besides a view's sources, the maps of every
  // other view of the run (--image_names, or all) whose viewing direction is within this angle
  // (degrees) of the view's (ViewsLookingTheSameWay in colmap_ext/source_views.h; 0: the
  // sources only, as COLMAP). Matching needs views that look alike, consistency only views
  // that see the same hair: a gantry's T group matches within its 10 degrees, but its
  // neighbouring groups, 35-60 degrees away, check its depths over baselines four times
  // longer. 90: beyond it a view sees the reference's hair from behind. Measured (.geometric
  // maps; 0 / 50 / 70 / 90): synth_straight_gantry 98.8 / 98.6 / 98.6 / 98.6% of the hair at a
  // per-pixel median of 4.58 / 4.34 / 4.31 / 4.31 mm, mean 9.89 / 8.21 / 8.06 / 8.06, 3D mean
  // 1.586 / 1.316 / 1.223 / 1.227 mm, 3D median 0.575 / 0.560 / 0.559 / 0.560 mm, the prior
  // 10 / 25 / 40 / 51 s of 155-238 s (3 sources and 3-8 / 6-15 / 8-20 views more; 15 s at 90
  // since the prior runs only at the masks' pixels);
  // synth_handheld (6 sources and 0-1 / 0-2 / 2-6 views more) 93.4 / 92.6 / 93.2 / 92.5% at
  // 5.61 / 5.70 / 5.52 / 5.38 mm, mean 11.39 / 11.59 / 11.11 / 10.79, 3D median 0.647 / 0.653 /
  // 0.639 / 0.627 mm (50: 2 rounds instead of 3). A lone T group has no such views.
  double geom_consistency_max_view_angle_deg = 90.0;
  // Of those views, at most this many, the nearest in direction: the prior and the filter read
  // each one's map, so that without a bound a large workspace's geometric pass grows with the
  // square of its views (and the prior's device buffer with their number). 30: the shared sets'
  // views have at most 22. 0: the sources only.
  int geom_consistency_max_num_views = 30;
  double geom_consistency_min_inconsistent_fraction = 0.1;
  double geom_consistency_min_gain = 0.01;
  // Estimate on the part of the view that holds its mask (the bounding box, grown past every
  // window's reach and aligned to the pyramid) rather than on the whole image: outside the
  // mask the data term is 0 and no depth is kept, yet the aggregation, the MRF and the prior
  // cost as much per pixel there. The shared sets' masks cover a fifth of their views and their
  // boxes under a third. Inside the mask the maps are those of the whole image up to the MRF's
  // paths, which start at the crop's edge. Measured (off / on, the prior at the masks' pixels
  // either way): synth_straight_gantry 159 / 113 s (the MRF 47 / 23 s, the aggregation 41 / 20
  // s), peak 1.9 / 1.4 GB, per-pixel median 4.31 / 4.32 mm; synth_handheld 111 / 75-82 s, 1.2 /
  // 0.9 GB, 5.37 / 5.41 mm; a 1404 x 936 T group 21.9 s in the stage table (4 views; 45 s before
  // both savings; 19.2 s with the filters' fixed work-groups).
  bool crop_to_mask = true;
  // Memory (MiB) for keeping each view's coarse volume (all labels, aggregated), depth range
  // and visual-hull bound from the first estimate to the geometric pass, which would compute
  // them again (width x height x 36 bytes a view: 22 MiB at 960 x 640); views beyond it are
  // computed again.
  int coarse_volume_cache_mib = 2048;
  // Only the geometric pass, on the existing .photometric maps.
  bool geom_consistency_only = false;
  // As colmap patch_match_stereo does (always, there; `hairmvs patch_match_stereo` too): a view
  // whose .geometric depth and normal maps exist is skipped, and one whose .photometric maps
  // exist starts at the geometric pass, so that an interrupted run resumes where it stopped.
  // Off by default for orientation_stereo: maps already there are those of the options they
  // were made with, not of this run's. A view estimated again loses its .geometric maps when
  // its new .photometric ones are written. Refused with geom_consistency_only, which redoes the
  // .geometric maps that the first pass wrote.
  bool skip_existing = false;
  // Reuse / write stereo/orientation_maps/<name>.l<k>.bin. Cached fields are reused only while
  // their <name>.provenance.txt matches the image, the mask, the processing size and the
  // --OrientationField options in use; otherwise they are computed again (and the log says
  // which of these changed).
  bool reuse_orientation_maps = true;
  bool write_orientation_maps = true;
  // Also write coloured depth and normal pictures (PNG): each command's own --write_png, not
  // an option of this section (one option for one thing).
  bool write_png = false;
  // Also write each view's coarse data term as first estimated (aggregated, all labels, before
  // the geometric prior and the hull bound) to stereo/cost_volumes/<name>.coarse.bin (a Mat on
  // the coarse grid, one channel per depth label) and the labels' depths to
  // <name>.coarse.depths.txt, for `hairmvs evaluate_data_term`: how often the data term alone
  // finds the true depth, whatever the MRF makes of it. About 20 MiB a view at 960 x 640.
  bool write_cost_volume = false;

  template <typename Visitor>
  void ForEachField(Visitor&& v) {
    v("cost", &cost, "orientation|photometric|combined: what is matched");
    v("mask_path", &mask_path,
      "folder of masks <image name>.png (empty: <workspace>/masks if present)");
    v("max_image_size", &max_image_size, "longer side of the processing resolution (-1: full)");
    v("depth_min", &depth_min, "depth range start in metres (0 or -1: from the sparse points)");
    v("depth_max", &depth_max, "depth range end in metres (0 or -1: from the sparse points)");
    v("depth_range_from_mask", &depth_range_from_mask,
      "depth range from the sparse points inside the mask (COLMAP's rule on them)");
    v("depth_range_from_visual_hull", &depth_range_from_visual_hull,
      "with masks: depth range from the masks' visual hull (sparse rule as fallback)");
    v("visual_hull_depth_bound", &visual_hull_depth_bound,
      "off|penalty|filter: with masks, no depth in front of where the ray enters the hull");
    v("visual_hull_tolerance_m", &visual_hull_tolerance_m,
      "tolerance of the visual hull depth bound in metres");
    v("visual_hull_min_carving_views", &visual_hull_min_carving_views,
      "a point leaves the hull when at least this many views see it outside their mask");
    v("visual_hull_mask_dilation_px", &visual_hull_mask_dilation_px,
      "dilate the other views' masks by this many px before carving the hull");
    v("depth_sampling", &depth_sampling, "depth|inverse_depth: label spacing");
    v("num_depths", &num_depths, "labels over the full depth range");
    v("num_levels", &num_levels, "orientation pyramid levels in the data term (paper: 3)");
    v("window_px_level0", &window_px_level0, "guided filter window at level 0 (finest), px (odd)");
    v("window_px_level1", &window_px_level1, "guided filter window at level 1, px (odd)");
    v("window_px_level2", &window_px_level2, "guided filter window at level 2, px (odd)");
    v("guide_rms", &guide_rms,
      "scale the reference field to this RMS magnitude as guide and smoothness weight (0: off)");
    v("guided_filter_eps", &guided_filter_eps, "guided filter eps (paper: 0.12)");
    v("sigma_o", &sigma_o, "smoothness weight orientation scale (paper: 0.15)");
    v("lambda", &lambda,
      "smoothness weight per squared coarse label, at lambda_label_step_px");
    v("lambda_label_step_px", &lambda_label_step_px,
      "the labels' disparity step (px per label for a source one radian away, in the middle of "
      "the range) at which lambda is given: each view's lambda is scaled by (its step / this)^2, "
      "so that the smoothness's quadratic part is the same at any image size and num_depths "
      "(truncation_labels is not scaled; 0: lambda per label as given; else at least 0.01)");
    v("truncation_labels", &truncation_labels,
      "truncate the quadratic smoothness at this label difference (<= 0: none)");
    v("mrf_solver", &mrf_solver, kMrfSolverNameList);
    v("mrf_max_cycles", &mrf_max_cycles,
      "graph_cuts' expansion cycles, icm's sweeps (semi_global and belief_propagation do not "
      "take it)");
    v("mrf_icm_polish_iterations", &mrf_icm_polish_iterations,
      "ICM sweeps polishing the MRF solver's labels (0: none)");
    v("coarse_level", &coarse_level,
      "orientation level whose grid the full-range MRF uses (-1: single stage at full size)");
    v("coarse_first_level", &coarse_first_level,
      "finest pyramid level in the coarse stage's data term (0: all; at most coarse_level)");
    v("coarse_labels_from_visual_hull", &coarse_labels_from_visual_hull,
      "with masks: coarse labels start at the visual hull's bound at each pixel");
    v("coarse_smoothness_along_visual_hull", &coarse_smoothness_along_visual_hull,
      "with coarse_labels_from_visual_hull: coarse smoothness on the depth behind the hull");
    v("level0_weight_angle_deg", &level0_weight_angle_deg,
      "level 0's weight per source: (this / view angle)^power in [1/4, 4] (0: levels alike)");
    v("level0_weight_angle_power", &level0_weight_angle_power,
      "exponent of level0_weight_angle_deg's weight");
    v("match_source_scale", &match_source_scale,
      "match each source's pyramid level to the scale at which it images the hair");
    v("fine_num_labels", &fine_num_labels, "labels of the fine band around the coarse depth");
    v("fine_label_step", &fine_label_step, "fine label spacing in coarse labels");
    v("slice_block", &slice_block, "depth slices per kernel launch");
    v("subpixel_refinement", &subpixel_refinement, "parabola sub-label refinement (Eq. 9)");
    v("final_guided_filter", &final_guided_filter, "guided-filter the depth map (Eq. 10)");
    v("min_confidence", &min_confidence, "depth 0 where the cost margin is below this");
    v("filter_range_ends", &filter_range_ends, "depth 0 at the first / last label");
    v("orientation_transfer", &orientation_transfer,
      "off|epipole_roll|plane_homography: how reference orientations enter a source view");
    v("strand_plane_from_visual_hull", &strand_plane_from_visual_hull,
      "plane_homography: strands lie parallel to the masks' visual hull (else fronto-parallel)");
    v("max_strand_plane_tilt_deg", &max_strand_plane_tilt_deg,
      "clamp the strand plane's tilt from the image plane at this angle (degrees)");
    v("orientation_normalization_radius_px", &orientation_normalization_radius_px,
      "match (O - local mean) / local std over this window radius (0: raw O, the paper)");
    v("orientation_normalization_eps", &orientation_normalization_eps,
      "regulariser of the local variance in the normalisation (x the field's mean |O|^2)");
    v("ncc_window_px", &ncc_window_px, "photometric and combined costs: NCC window in px (odd)");
    v("photometric_weight", &photometric_weight,
      "combined cost: the photometric cost's share of the data term, in [0, 1]");
    v("best_source_fraction", &best_source_fraction,
      "per pixel and depth, sum only this fraction of the sources, those matching best (1: all)");
    v("geom_consistency", &geom_consistency,
      "write .photometric (as estimated) and .geometric (consistency-filtered) maps");
    v("single_pass_type", &single_pass_type,
      "geometric|photometric: the maps' name without geom_consistency");
    v("geom_consistency_max_error_px", &geom_consistency_max_error_px,
      "consistency: largest forward-backward reprojection error in px");
    v("geom_consistency_min_views", &geom_consistency_min_views,
      "consistency: views that must agree for a pixel to keep its depth (its sources and, "
      "per geom_consistency_max_view_angle_deg, the views looking the same way)");
    v("geom_consistency_max_num_views", &geom_consistency_max_num_views,
      "consistency and prior: at most this many views looking the same way, the nearest in "
      "direction (besides the sources; 0: the sources only)");
    v("geom_consistency_min_triangulation_angle_deg",
      &geom_consistency_min_triangulation_angle_deg,
      "consistency: a view meeting the pixel's ray at a smaller angle does not count");
    v("geom_prior_weight", &geom_prior_weight,
      "geometric pass: weight of the sources' depth maps as a prior (0: filter only)");
    v("geom_prior_max_error_px", &geom_prior_max_error_px,
      "geometric pass: reprojection error (px) at which the prior costs the most");
    v("crop_to_mask", &crop_to_mask,
      "estimate on the mask's bounding box (with a margin) rather than the whole image");
    v("coarse_volume_cache_mib", &coarse_volume_cache_mib,
      "MiB for keeping the coarse volumes from the first estimate to the geometric pass");
    v("geom_consistency_iterations", &geom_consistency_iterations,
      "most rounds of the geometric pass, each with the previous round's maps as the prior");
    v("geom_consistency_max_view_angle_deg", &geom_consistency_max_view_angle_deg,
      "geometric pass: also the maps of the views whose optical axis is within this angle");
    v("geom_consistency_min_inconsistent_fraction", &geom_consistency_min_inconsistent_fraction,
      "another round only while at least this fraction of the depths is inconsistent");
    v("geom_consistency_min_gain", &geom_consistency_min_gain,
      "from the third round on, another only while the last added this consistent fraction");
    v("geom_consistency_only", &geom_consistency_only,
      "only the geometric pass (prior and filter), on the existing .photometric maps");
    v("skip_existing", &skip_existing,
      "resume: skip views whose maps exist (as colmap patch_match_stereo; see the header)");
    v("reuse_orientation_maps", &reuse_orientation_maps,
      "reuse stereo/orientation_maps/*.l<k>.bin made from this image, mask, size and filter");
    v("write_orientation_maps", &write_orientation_maps,
      "write computed orientation fields to stereo/orientation_maps/");
    v("write_cost_volume", &write_cost_volume,
      "write the coarse data term to stereo/cost_volumes/ (for evaluate_data_term)");
  }
  bool Check(std::string* error) const;
  // Window in px of a level (levels beyond 2 reuse the level-2 window).
  int WindowPx(int level) const;
  // The factor of a source `view_angle_deg` away from the reference in the orientation cost of
  // `level` (of num_levels used): level0_weight_angle_deg's weights, averaging 1 over the levels.
  double LevelSourceWeight(int level, int num_levels, double view_angle_deg) const;
  // The smoothness weight of a view whose labels step label_step_px (LabelStepPxPerRadian):
  // lambda scaled by lambda_label_step_px, or as given without the scaling or a step (0).
  double ViewLambda(double label_step_px) const;
  // Orientation pyramid levels to compute: the data term's and the coarse stage's grid.
  int PyramidLevels() const { return std::max(num_levels, coarse_level + 1); }
  // The fields this stereo reads: `filter`'s with PyramidLevels() levels (what orientation
  // fields computed for it must be, to be reused).
  OrientationFieldOptions FieldOptions(const OrientationFieldOptions& filter) const;
  // The --OrientationField options that FieldOptions sets, with why: a command that takes both
  // sections adds these as ignored (OptionParser::AddSection), so giving one warns.
  static std::map<std::string, std::string> FieldOptionsSetHere() {
    return {{"num_levels",
             "the stereo computes the fields' levels from --OrientationStereo.num_levels and "
             "coarse_level"}};
  }
  // The name of the maps a view ends with: "geometric" after the geometric pass, else
  // single_pass_type.
  std::string FinalMapType() const { return geom_consistency ? "geometric" : single_pass_type; }
  // Whether the data term matches orientation fields (orientation or combined cost).
  bool MatchesOrientation() const { return cost != StereoCost::kPhotometric; }
  // Whether the data term matches colours (photometric or combined cost).
  bool MatchesColour() const { return cost != StereoCost::kOrientation; }
  // The single costs the data term sums, each with its weight: the cost itself with 1, or for
  // the combined cost orientation with 1 - photometric_weight and colour with photometric_weight.
  std::vector<std::pair<StereoCost, float>> DataTerms() const;
  // How many of num_sources sources the data term sums at each pixel and depth
  // (best_source_fraction): at least 1.
  int NumBestSources(int num_sources) const;
  // Whether the orientation cost carries strands through planes tilted as the visual hull
  // (strand_plane_from_visual_hull with an orientation-matching cost and plane_homography).
  bool StrandPlaneFromVisualHull() const;
};

struct OrientationStereoResult {
  int num_views = 0;
  // With skip_existing: views left as they were, and views whose first estimate was read.
  int num_skipped = 0;
  int num_resumed_at_geometric_pass = 0;
  int geometric_rounds = 0;  // rounds of the geometric pass that ran
  std::vector<std::string> depth_map_paths;
  double seconds = 0;
  double peak_memory_mib = 0;
  std::string BriefReport() const;
};

// Computes depth maps for `image_names` (empty: every image of the workspace). `device_spec`
// picks the OpenCL device ("" = first GPU, else first CPU; an index; or a name substring).
// `source_views` chooses the source views (null: SourceViewOptions' defaults, 6 views); an
// explicit patch-match.cfg list is capped to its max_num_source_views. `field_options` (null:
// OrientationFieldOptions' defaults) computes the orientation fields that are not cached in
// stereo/orientation_maps/ with these options (its num_levels is replaced by
// options.PyramidLevels()).
// Throws hairmvs::Error for bad input (unknown image, missing files, bad options).
OrientationStereoResult RunOrientationStereo(const std::string& workspace_path,
                                             const std::vector<std::string>& image_names,
                                             const OrientationStereoOptions& options,
                                             StageTimings* timings,
                                             const std::string& device_spec = "",
                                             const SourceViewOptions* source_views = nullptr,
                                             const OrientationFieldOptions* field_options =
                                                 nullptr);

// What the workspace holds of a view already (`hairmvs workspace_info`), so that a user or a
// cluster's array sees what is left to run.
struct ViewOutputs {
  std::string name;
  enum class Fields { kNone, kUpToDate, kStale };
  // The cached orientation fields, against what RunOrientationStereo with these options would
  // compute: its processing size (max_image_size) and pyramid levels, and `field_options`.
  Fields fields = Fields::kNone;
  std::string why_stale;  // the provenance line that no longer holds, or what is missing
  bool photometric_maps = false;  // .photometric depth and normal maps
  bool geometric_maps = false;
};
std::vector<ViewOutputs> WorkspaceOutputs(const std::string& workspace_path,
                                          const OrientationStereoOptions& options,
                                          const OrientationFieldOptions& field_options);

}  // namespace hairmvs
