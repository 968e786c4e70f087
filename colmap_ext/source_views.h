#pragma once
// Which source views each reference view is matched against, and per-view depth ranges.
//
// stereo/patch-match.cfg is honoured as COLMAP reads it (colmap-formats.md section 3): pairs of
// lines "reference" / "sources", sources being an explicit list (`,` or `;`), `__all__`, or
// `__auto__, N`. For `__auto__` (and for every image when there is no cfg) hairmvs does not
// simply take COLMAP's top-N by shared sparse points: orientation matching is blind to strands
// parallel to the epipolar lines, so the chosen set should span different epipolar directions
// at the reference. Candidates pass COLMAP's triangulation-angle test (75th percentile >=
// min_triangulation_angle_deg; wider than max_triangulation_angle_deg only as a last resort);
// then a greedy choice scores each candidate by
//   shared_points / max_shared_points * (1 + epipolar_spread_weight * spread),
// spread = (smallest angle, modulo pi, between its epipolar direction at the reference image
// centre and those already chosen) / (pi/2), in [0, 1]; spread = 1 for the first pick.
// A gantry T group (paper section 3: centre with left, right and bottom views) is recognised
// and chosen first.

#include <cstdint>
#include <string>
#include <vector>

#include "colmap_ext/reconstruction.h"
#include "colmap_ext/workspace.h"

namespace hairmvs {

struct SourceViewOptions {
  // Upper bound on the sources of a reference: caps `__auto__, N` of the cfg, and an explicit
  // list or `__all__` keeps the views sharing the most sparse points with the reference.
  // A gantry T group's views share points only with each other (3 sources); handheld views
  // see 7-18 candidates, and more sources give the geometric pass more maps to agree with.
  // Measured (.geometric maps, 4 -> 6 -> 8): synth_handheld 74.5 -> 80.3 -> 81.7% covered,
  // per-pixel median 5.85 -> 5.75 -> 5.76 mm, 3D mean 2.68 -> 2.13 -> 2.13 mm, 95 -> 95 ->
  // 110 s; synth_straight_gantry's g0 and g3 groups (the only views that share points with
  // another group) 4.45 -> 4.45 -> 4.43 mm. Sources of the next group given by hand (a
  // patch-match.cfg; g2_c alone, no geometric pass): its T group 4.02 mm, + g7_b (35 degrees
  // away) 3.91, + g7_b, g7_c and g7_l 3.94; one source alone: g2_r 3.88, g2_l 4.35, g2_b
  // (baseline along the hanging strands) 8.19 mm. All 32 views, each with its T group and the
  // 1 / 3 views of other groups nearest in viewing direction (28-50 degrees; a cfg by hand):
  // 98.4% / 7.54 / 4.10 mm and 98.6% / 7.78 / 4.13 mm (complete / per-pixel mean / median)
  // against 98.7% / 7.93 / 4.17, in 299 / 399 s. Wider sources hardly help orientation.
  // The g2 group alone (both passes, 99.6% / 6.07 / 4.02 mm with its T group; measured on
  // c68eb65): each view with g7_c, g7_l and g7_b too (35-41 degrees away) 98.6% / 5.79 / 3.98
  // mm, with g0_r and g5_l (50 degrees, beside the group) 97.2% / 5.79 / 3.93 mm. They take
  // the silhouette band from 5.89 to 5.46 / 5.50 mm (signed +1.57 -> +0.62 / -0.05: the
  // hanging ends no longer fall behind), but push the interior further to the front (signed
  // -2.14 -> -2.46 / -2.41 mm): across a wider baseline more of the deeper first hits, seen
  // through gaps in the reference, are hidden in the source. Alone, each of these wide sources
  // fails (g2_c, one pass: 8-47 mm against 4.1 mm with g2_l or g2_r alone).
  int max_num_source_views = 6;
  // COLMAP's PatchMatchStereo.min_triangulation_angle: 75th percentile of the shared points'
  // triangulation angles must reach this.
  double min_triangulation_angle_deg = 1.0;
  // Candidates wider than this (75th percentile) are used only when no others are left: the
  // paper's rig has about 10 degrees between neighbours; at 60 degrees hair looks different.
  double max_triangulation_angle_deg = 40.0;
  // Weight of the epipolar-direction spread bonus (0 = COLMAP's ranking by shared points).
  double epipolar_spread_weight = 2.0;
  // Read stereo/patch-match.cfg (or config_path) when it exists.
  bool use_config = true;
  std::string config_path;  // "" = <workspace>/stereo/patch-match.cfg
  // Gantry T group: epipolar directions at the reference centre within this angle of the
  // image axes, optical axes within t_group_max_view_angle_deg of the reference's, baseline
  // lengths within this ratio (largest / smallest) of each other.
  double t_group_max_axis_angle_deg = 20.0;
  double t_group_max_view_angle_deg = 30.0;
  double t_group_max_distance_ratio = 1.5;

  template <typename Visitor>
  void ForEachField(Visitor&& v) {
    v("max_num_source_views", &max_num_source_views,
      "most source views per reference (caps `__auto__, N` of patch-match.cfg; longer lists "
      "and __all__ keep the views sharing the most sparse points)");
    v("min_triangulation_angle_deg", &min_triangulation_angle_deg,
      "75th percentile of shared points' triangulation angles must reach this (COLMAP: 1)");
    v("max_triangulation_angle_deg", &max_triangulation_angle_deg,
      "candidates wider than this (75th percentile) are used only when no others are left");
    v("epipolar_spread_weight", &epipolar_spread_weight,
      "bonus for candidates whose epipolar direction differs from those chosen (0 = COLMAP)");
    v("use_config", &use_config, "honour stereo/patch-match.cfg when it exists");
    v("config_path", &config_path, "patch-match.cfg to use instead of stereo/patch-match.cfg");
    v("t_group_max_axis_angle_deg", &t_group_max_axis_angle_deg,
      "gantry T group: epipolar directions within this angle of the image axes");
    v("t_group_max_view_angle_deg", &t_group_max_view_angle_deg,
      "gantry T group: optical axes within this angle of the reference's");
    v("t_group_max_distance_ratio", &t_group_max_distance_ratio,
      "gantry T group: largest/smallest baseline length");
  }
  bool Check(std::string* error) const;
};

struct SourceViewSelection {
  std::string reference;
  std::vector<std::string> sources;
  std::string reason;
  bool gantry_t_group = false;
  // Per source (same order): shared sparse points, 75th-percentile triangulation angle (deg),
  // and epipolar direction at the reference image centre (deg, modulo 180, from +x towards +y).
  std::vector<int> shared_points;
  std::vector<double> triangulation_angle_deg;
  std::vector<double> epipolar_direction_deg;
};

// One selection per reference: the references of the cfg in its order, or every image of the
// workspace in image_idx order when there is no cfg (or use_config is false). References
// whose source list comes out empty are dropped, as COLMAP does. Throws hairmvs::Error for a
// malformed cfg (naming the file and line).
std::vector<SourceViewSelection> SelectSourceViews(const Workspace& ws,
                                                   const SourceViewOptions& options);

// The views of the workspace, other than `reference` and those in `exclude`, whose viewing
// direction is within max_view_angle_deg of the reference's, in image_idx order. The geometric
// pass checks a depth map against these besides its sources: consistency needs only that a view
// sees the same side of the hair, not that it looks alike, so it can use the wider baselines
// that orientation matching cannot (a gantry's neighbouring T groups, 35-60 degrees away).
std::vector<std::string> ViewsLookingTheSameWay(const Workspace& ws, const std::string& reference,
                                                const std::vector<std::string>& exclude,
                                                double max_view_angle_deg);

// Of `candidates` (names of the workspace's images), the `max_num_views` whose viewing
// directions lie nearest the reference's, in their order in `candidates`; all of them when
// there are no more (ties keep the earlier).
std::vector<std::string> NearestInDirection(const Workspace& ws, const std::string& reference,
                                            const std::vector<std::string>& candidates,
                                            size_t max_num_views);

struct DepthRange {
  double min_m = -1;
  double max_m = -1;
  int num_points = 0;
  bool inside_mask = false;  // from the points inside a mask only (not the fallback)
};
// COLMAP's Model::ComputeDepthRanges: depths d > 0 of the sparse points in the image's tracks,
// sorted; [0.75 * d[floor(0.01 n)], 1.25 * d[floor(0.99 n)]]; (-1, -1) when there are none.
DepthRange ComputeDepthRange(const Reconstruction& model, uint32_t image_id);
// The same rule over the sparse points whose observation in this image falls inside `mask`
// (1 = keep; any size: observations are scaled from the camera's size to the mask's). A hair
// mask thus keeps the room behind the subject out of the range. Falls back to all points when
// fewer than `min_points` observations are inside the mask.
DepthRange ComputeDepthRange(const Reconstruction& model, uint32_t image_id,
                             const FloatMap& mask, int min_points = 10);

// The epipolar direction, modulo pi, at image point `point_px` of the reference: the direction
// of the line through `point_px` and the source camera centre projected into the reference.
double EpipolarDirectionRad(const Reconstruction& model, uint32_t reference_id,
                            uint32_t source_id, const Eigen::Vector2d& point_px);

// --- The cfg files.
struct PatchMatchProblem {
  enum class Kind { kExplicit, kAll, kAuto };
  std::string reference;
  Kind kind = Kind::kAuto;
  std::vector<std::string> sources;  // kExplicit
  int num_auto = 0;                  // kAuto: N of `__auto__, N`
  int line_number = 0;               // of the sources line, for messages
};
// Throws hairmvs::Error naming `path` and the line for: a reference without a sources line,
// `__auto__` without exactly one positive N, an empty name, a name that is not an image of
// `model`, a reference listing itself.
std::vector<PatchMatchProblem> ReadPatchMatchConfig(const std::string& path,
                                                    const Reconstruction& model);
// fusion.cfg: one image name per line; COLMAP does not skip `#` lines there (it aborts), so a
// `#` line is an error here too.
std::vector<std::string> ReadFusionConfig(const std::string& path, const Reconstruction& model);
// Writers (atomic) in the formats above.
void WritePatchMatchConfig(const std::string& path, const std::vector<PatchMatchProblem>& problems);
void WriteFusionConfig(const std::string& path, const std::vector<std::string>& image_names);

}  // namespace hairmvs
