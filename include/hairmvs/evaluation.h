#pragma once
// Evaluation against the exact ground truth of the synthetic data sets (shared/data/README.md):
//   - ImportGroundTruth: a dense workspace whose depth and normal maps are the truth (plus
//     noise if asked), for testing the stages after stereo;
//   - EvaluateDepthMaps: per-pixel depth errors and completeness on the hair pixels, and the
//     3D distance of the back-projected depths to the true strands;
//   - EvaluateMesh: accuracy (mesh to strands) and completeness (visible true hair surface to
//     mesh), as the DTU benchmark measures them.
// Distances are reported in millimetres (fields *_mm), inputs are in metres (*_m).

#include <limits>
#include <string>
#include <vector>

namespace hairmvs {

class StageTimings;  // src/core/timer.h

struct ImportGroundTruthOptions {
  // Standard deviation of the Gaussian noise added to every written depth (0 = exact).
  double noise_m = 0.0;
  int seed = 0;
  // Keep only hair pixels (label 2); otherwise hair and head skin (labels 1, 2).
  bool hair_only = false;
  // Median-filter the true depth maps (k x k over the kept pixels, 0 = off) before writing:
  // the README's "ideal smooth surface" (7). At most kMaxMedianFilterPx: each pixel sorts
  // k^2 depths, and a window of the image's size is no longer a surface's local shape.
  int median_filter_px = 0;
  static constexpr int kMaxMedianFilterPx = 99;
  // 1: a plain median (background zeros count; every pixel filtered, then the labels
  // applied); 0: the median of the kept depths around each kept pixel.
  bool median_include_background = true;
  // Copy images/ and masks/ instead of symlinking them.
  bool copy_images = false;
  // Empty: every image of the workspace.
  std::vector<std::string> image_names;

  template <typename Visitor>
  void ForEachField(Visitor&& v) {
    v("noise_m", &noise_m, "std. dev. of Gaussian noise added to the true depths (m)");
    v("seed", &seed, "random seed of the noise");
    v("hair_only", &hair_only, "keep hair pixels only (else hair and head skin)");
    v("median_filter_px", &median_filter_px,
      "median-filter the true depths over a k x k window (0 = off; odd, at most 99)");
    v("median_include_background", &median_include_background,
      "plain median with background zeros (1) or of the kept depths only (0)");
    v("copy_images", &copy_images, "copy images/ and masks/ instead of symlinking");
    v("image_names", &image_names, "views to write (comma-separated; empty = all)");
  }
  bool Check(std::string* error) const;
};

struct ImportGroundTruthResult {
  std::string output_path;
  int num_views = 0;
  double kept_pixel_fraction = 0;  // of all pixels, over the views
  std::string Report() const;
};

// Writes a new workspace `output_path` (never inside the shared data): sparse/ copied from the
// workspace, images/ and masks/ linked (or copied), stereo/{patch-match,fusion}.cfg copied,
// stereo/depth_maps/<name>.geometric.bin (true z-depth, SfM pixel convention, 0 outside the
// kept labels) and stereo/normal_maps/<name>.geometric.bin (camera-frame normals of that
// depth map). The workspace's cameras must have the ground truth's image size.
ImportGroundTruthResult ImportGroundTruth(const std::string& ground_truth_path,
                                          const std::string& workspace_path,
                                          const std::string& output_path,
                                          const ImportGroundTruthOptions& options,
                                          StageTimings* timings = nullptr);

struct DepthEvaluationOptions {
  std::string depth_type = "geometric";
  // Empty: every image of the workspace that has a depth map of depth_type.
  std::vector<std::string> image_names;
  // Error pictures and the JSON go here; empty = <workspace>/stereo/evaluation.
  std::string output_path;
  bool write_error_images = true;
  // Colour scale of the error pictures: 0 (blue) to this (red), in mm.
  double error_image_max_mm = 10.0;
  // 3D accuracy from at most this many randomly chosen pixels per view (0 = all); in the
  // overall row each view's sample stands for all of its pixels with a depth.
  int max_points_3d_per_view = 0;
  int seed = 0;
  // Spline sampling of the true strands (StrandDistance): distances are to the polyline through
  // the samples, within spacing^2 / (8 x radius of curvature) of the spline: 1 mm gives < 0.03
  // mm for curls of 4 mm radius (~6 mm radius of curvature) and 5x fewer samples than 0.2 mm
  // (100 000 curly strands: index built in 8 s instead of 39 s, 3.7 GB -> ~0.9 GB).
  double strand_spacing_m = 1e-3;
  // The per-pixel error is also reported separately for the hair pixels within this many
  // (depth-map) pixels of the background and for those further in: hair turning away at the
  // silhouettes, its fuzzy edge and its loose ends weigh on the median differently from the
  // hair lying on the head (synth_straight_gantry, all 32 views, its true depth maps
  // median-filtered 7 x 7: 3.23 mm within 20 px, 41% of the hair, and 1.75 mm further in).
  // 0: every hair pixel counts as inside.
  int silhouette_band_px = 20;
  // Which layer of the hair the depths follow: for each hair pixel with a depth whose k x k
  // window (true depth map pixels, k = this) is all hair, the fraction of the window's true
  // depths in front of it (ties count half); the median over those pixels is reported. Hair
  // is a volume seen through gaps between thin strands: each pixel's truth is the first strand
  // its centre ray hits, so the true depths of a window scatter over millimetres, and 50% is
  // the window's median, the README's ideal smooth surface. Below 50% the depths follow the
  // front of the hair, above it the strands behind. 0: not computed.
  int layer_window_px = 7;
  // The per-pixel error split by scale: its smooth part, the signed errors averaged over a k x k
  // window of the map (k = this; the hair pixels with a depth), is what a surface wrong at that
  // scale errs by, and the rest (each error less that average) what a surface right at that
  // scale would still err by: the hair's layering, which only a depth per strand follows, and
  // the map's own finer errors. The medians of both are reported. 31 px: about the reach of the
  // coarsest level's aggregation window at 960 x 640. 0: not computed.
  int smooth_error_window_px = 31;
  // Where a depth is compared with the truth. On: in the view's true camera (gt/cameras.npz;
  // where the map is smaller, the true pixel each map pixel's centre lies in), each true hair
  // pixel is compared with the map where the ray through its centre meets it: the ray's point
  // at the map's depth there in the workspace's camera (read between the map's pixel centres,
  // SampleDepthMap), as a z-depth in the true camera; a true hair pixel whose ray meets no
  // depth is missing. So every true hair pixel
  // counts once, as the same index does, rather than wherever the map's depths happen to
  // land. Off: every depth is compared with the true
  // pixel of the same index. The two are the same where the workspace's cameras are the true
  // ones (the gantry sets: sparse/ holds the true poses); where they come from COLMAP's mapper
  // (synth_handheld: its poses are 0.24-0.43 degrees off the truth), the same index is a
  // different ray, 1-3 px away at the hair (h13: 13 px), and the per-pixel error of a layered
  // hair then measures the poses as much as the depths. import_ground_truth writes the true
  // poses with the true maps, so those meet the truth exactly in either mode.
  bool in_true_cameras = true;

  template <typename Visitor>
  void ForEachField(Visitor&& v) {
    v("depth_type", &depth_type, "geometric or photometric");
    v("image_names", &image_names, "views to evaluate (comma-separated; empty = all)");
    v("output_path", &output_path,
      "folder for error pictures and JSON (default W/stereo/evaluation)");
    v("write_error_images", &write_error_images,
      "write <name>.error.png and <name>.signed_error.png per view");
    v("error_image_max_mm", &error_image_max_mm, "error at the red end of the colour scale (mm)");
    v("max_points_3d_per_view", &max_points_3d_per_view,
      "subsample the 3D accuracy to this many pixels per view (0 = all)");
    v("seed", &seed, "random seed of the subsampling");
    v("strand_spacing_m", &strand_spacing_m, "spline sampling of the true strands (m)");
    v("silhouette_band_px", &silhouette_band_px,
      "hair pixels this close to the background count as near the silhouette (px)");
    v("layer_window_px", &layer_window_px,
      "k x k window (odd) of true depths that ranks the layer of each depth (0 = off)");
    v("smooth_error_window_px", &smooth_error_window_px,
      "k x k window (odd) whose mean signed error is the smooth part of the error (0 = off)");
    v("in_true_cameras", &in_true_cameras,
      "compare each true hair pixel with the map where its ray meets it, in the true camera (1), "
      "or with the map's pixel of the same index (0)");
  }
  bool Check(std::string* error) const;
};

struct DepthMetrics {
  std::string name;  // image name, or "overall"
  long num_hair_pixels = 0;
  long num_with_depth = 0;       // hair pixels with a depth > 0
  double completeness = 0;       // num_with_depth / num_hair_pixels
  // Depths > 0 where the truth is background (beyond the hair's silhouette), and their share of
  // the depths on hair or background.
  long num_background_depths = 0;
  double background_depth_fraction = 0;
  // |depth - true depth| on hair pixels with a depth.
  double mean_abs_error_mm = 0;
  double median_abs_error_mm = 0;
  double within_1mm = 0;  // fractions of num_with_depth
  double within_2mm = 0;
  double within_5mm = 0;
  // Median of depth - true depth: > 0 behind the truth, < 0 in front of it.
  double median_signed_error_mm = 0;
  // The hair pixels with a depth within DepthEvaluationOptions::silhouette_band_px of the
  // background (fraction of num_with_depth), and the median absolute and signed errors there
  // and on the others (the interior).
  double silhouette_fraction = 0;
  double silhouette_median_abs_error_mm = 0;
  double silhouette_median_signed_error_mm = 0;
  double interior_median_abs_error_mm = 0;
  double interior_median_signed_error_mm = 0;
  // Median layer of the depths (DepthEvaluationOptions::layer_window_px): the fraction of the
  // true depths around a pixel in front of its depth, 0.5 = the local median of the truth.
  long num_layer_pixels = 0;
  double median_layer = 0;
  // Medians of |smooth part| and |rest| of the per-pixel error
  // (DepthEvaluationOptions::smooth_error_window_px); 0 when not computed.
  double smooth_median_abs_error_mm = 0;
  double rough_median_abs_error_mm = 0;
  // 3D: every depth on a true hair or background pixel (not on skin), back-projected with the
  // workspace's camera, distance to the nearest true strand.
  long num_points_3d = 0;
  double accuracy_3d_mean_mm = 0;
  double accuracy_3d_median_mm = 0;
  double accuracy_3d_p90_mm = 0;
};

struct DepthEvaluationResult {
  std::vector<DepthMetrics> views;
  DepthMetrics overall;  // pooled over all views' pixels
  std::string json_path;
  std::string Table() const;
};

// `timings`, when given, gets the time of each stage (reading, per-pixel errors, 3D distances...).
DepthEvaluationResult EvaluateDepthMaps(const std::string& workspace_path,
                                        const std::string& ground_truth_path,
                                        const DepthEvaluationOptions& options,
                                        StageTimings* timings = nullptr);

// The data term alone, without the MRF: per coarse pixel of a view's cost volume as
// `orientation_stereo --OrientationStereo.write_cost_volume 1` writes it, where its cheapest
// label lies against the true depth (the median true depth of the hair pixels the coarse pixel
// covers; the volume's grid is a level of the stereo's image pyramid, whose image coordinates
// halve exactly, so that for an odd size it reaches past the image). Compares costs
// (orientation vs photometric) on what they bring, before smoothing.
struct DataTermEvaluationOptions {
  // Empty: every image of the workspace that has a cost volume.
  std::vector<std::string> image_names;
  // A coarse pixel counts when at least this fraction of the image pixels it covers are hair.
  double min_hair_fraction = 0.5;
  // The JSON goes here; empty = <workspace>/stereo/evaluation.
  std::string output_path;
  // As DepthEvaluationOptions::in_true_cameras: each true hair depth, back-projected with the
  // true camera, counts in the coarse pixel of the workspace's camera it lands in, as a z-depth
  // there (1), or in the coarse pixel that holds its own pixel's centre (0).
  bool in_true_cameras = true;

  template <typename Visitor>
  void ForEachField(Visitor&& v) {
    v("image_names", &image_names, "views to evaluate (comma-separated; empty = all)");
    v("min_hair_fraction", &min_hair_fraction,
      "count a coarse pixel when at least this fraction of its image pixels are hair");
    v("output_path", &output_path, "folder for the JSON (default W/stereo/evaluation)");
    v("in_true_cameras", &in_true_cameras,
      "carry the true depths from the true cameras into the workspace's (1) or take them at "
      "the same pixels (0)");
  }
  bool Check(std::string* error) const;
};

struct DataTermMetrics {
  std::string name;  // image name, or "overall"
  long num_pixels = 0;          // coarse hair pixels whose true depth is inside the label range
  long num_outside_range = 0;   // coarse hair pixels whose true depth is outside it
  double label_step_mm = 0;     // median depth step between the labels around the true depths
  // |depth of the cheapest label - true depth|.
  double median_abs_error_mm = 0;
  // Median of (depth of the cheapest label - true depth): below 0 the data term leans to the
  // front of the hair, above 0 behind it.
  double median_signed_error_mm = 0;
  double within_1_label = 0;  // fractions of num_pixels: cheapest label within 1 label
  double within_5mm = 0;
  double within_10mm = 0;
  // Median over the pixels of the fraction of labels cheaper than the true depth (its cost
  // interpolated between the two labels around it): 0 = the truth is the data term's minimum.
  double median_true_depth_rank = 0;
};

struct DataTermEvaluationResult {
  std::vector<DataTermMetrics> views;
  DataTermMetrics overall;  // pooled over all views' pixels
  std::string json_path;
  std::string Table() const;
};

DataTermEvaluationResult EvaluateDataTerm(const std::string& workspace_path,
                                          const std::string& ground_truth_path,
                                          const DataTermEvaluationOptions& options,
                                          StageTimings* timings = nullptr);

struct MeshEvaluationOptions {
  // Accuracy also from points sampled on the faces, about this far apart (0 = vertices only).
  double face_sample_spacing_m = 5e-4;
  // Completeness distances are exact point-to-triangle distances; the faces are sampled this
  // densely for the KD-tree that finds the candidate faces (speed and memory only).
  double surface_sample_spacing_m = 5e-4;
  // True visible hair surface: hair pixels of every view, at most this many (random).
  int max_ground_truth_points = 300000;
  int seed = 0;
  double strand_spacing_m = 1e-3;  // as EvaluateDepthOptions::strand_spacing_m
  // JSON summary; empty = <workspace>/stereo/evaluation/mesh_evaluation.json when a workspace
  // is given, else <mesh>.evaluation.json.
  std::string output_json;

  template <typename Visitor>
  void ForEachField(Visitor&& v) {
    v("face_sample_spacing_m", &face_sample_spacing_m,
      "accuracy also from face samples this far apart (0 = vertices only)");
    v("surface_sample_spacing_m", &surface_sample_spacing_m,
      "face sampling of the KD-tree for exact point-to-mesh distances (m; speed only)");
    v("max_ground_truth_points", &max_ground_truth_points,
      "subsample of the visible true hair surface");
    v("seed", &seed, "random seed of the subsampling");
    v("strand_spacing_m", &strand_spacing_m, "spline sampling of the true strands (m)");
    v("output_json", &output_json, "JSON summary path");
  }
  bool Check(std::string* error) const;
};

// Of no values (a view without a depth): NaN, which the tables print as nan and the JSON
// summaries write as null, rather than an error of 0 mm that reads as perfect.
struct DistanceStats {
  long count = 0;
  double mean_mm = std::numeric_limits<double>::quiet_NaN();
  double median_mm = std::numeric_limits<double>::quiet_NaN();
  double p90_mm = std::numeric_limits<double>::quiet_NaN();
};

struct MeshEvaluationResult {
  long num_vertices = 0;
  long num_faces = 0;
  DistanceStats accuracy_vertices;  // mesh vertices to the nearest true strand
  DistanceStats accuracy_surface;   // points uniform over the faces (by area) to the nearest strand
  DistanceStats completeness_distance;  // true visible hair surface to the mesh
  double completeness_2mm = 0;  // fraction of the true visible hair surface within 2 mm
  double completeness_5mm = 0;
  std::string json_path;
  std::string Report() const;
};

// `workspace_path` may be empty; when given, the visible surface uses the views of the
// workspace only and the JSON goes into its stereo/evaluation folder.
MeshEvaluationResult EvaluateMesh(const std::string& mesh_path,
                                  const std::string& ground_truth_path,
                                  const std::string& workspace_path,
                                  const MeshEvaluationOptions& options,
                                  StageTimings* timings = nullptr);

}  // namespace hairmvs
