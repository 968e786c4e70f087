#pragma once
// The synthetic hair data set generator: procedural strands on an ellipsoidal head, rendered on
// the CPU from a camera rig, written with exact ground truth in the layout of the shared data
// sets (/work/shared/data/README.md): <output>/dense (a COLMAP dense workspace with the true
// poses, sparse points with tracks, masks) and <output>/gt (per-view depth and labels, cameras,
// strands, meta.json, pictures).

#include <string>

namespace hairmvs {

enum class HairStyle { kStraight, kCurly };
std::string ToString(HairStyle style);
bool FromString(const std::string& text, HairStyle* style);

enum class CameraRigType { kGantry, kHandheld };
std::string ToString(CameraRigType rig);
bool FromString(const std::string& text, CameraRigType* rig);

struct SynthesizeOptions {
  std::string output_path;
  HairStyle style = HairStyle::kStraight;
  // gantry: the paper's T groups of 4 (centre, left/right 10 degrees apart in azimuth, bottom
  // 10 degrees lower) at 0.6 m from the hair; handheld: views around the head at varied
  // distance, elevation and small roll. Either way the workspace's model holds the true
  // cameras: a handheld set here has no structure-from-motion error, unlike the shared
  // synth_handheld (its mapper's poses, off by 2.2 mm), so its figures are the better ones.
  CameraRigType rig = CameraRigType::kGantry;
  // Gantry groups (1..8, in the order of the shared set: back, back-left, back-right, top...).
  int num_groups = 1;
  // Handheld views; 0 = 4 * num_groups.
  int num_views = 0;
  // Image width; height = round(2/3 width), focal = 0.79977 width (the shared sets' lens).
  // 960, as the shared sets: at 0.6 m one pixel of disparity between the 10-degree views of a
  // T group is ~4.5 mm of depth at 960 px, ~9 mm at 480 (too coarse for a 3 mm depth error).
  int width = 960;
  int seed = 1;
  // Strands: a human head has about 100 000 hairs. Fewer make a see-through volume rather than
  // a head of hair: the true depth maps of a curly T group, median-filtered 7 x 7 (an ideal
  // smooth surface), score a per-pixel median of 3.8 / 2.6 / 2.0 mm against themselves with
  // 12k / 40k / 100k strands (the shared straight set: 2.2 mm with 40k). Rendering costs
  // ~0.5 s per 1000 strands for a T group on 2 cores.
  int num_strands = 100000;
  // Render these strands instead of generating them: a folder holding strands_points.npy and
  // strands_offsets.npy (a data set's gt/, as its README describes them). num_strands is then
  // not used, style only sets the spline sampling (curly: finer). hairmvs's renderer shows the
  // same geometry as a shared set without its path tracer's look: synth_straight_gantry's
  // strands, 8 T groups, give a per-pixel median of 4.55 mm (97.1% of the hair; Blender's
  // renders 4.32 mm, 98.6%), while hairmvs's own straight hair gives 2.66 mm: the shared set's
  // error is its hair's geometry, not its rendering.
  std::string strands_path;
  double hair_root_diameter_m = 0.00016;
  double hair_tip_diameter_m = 0.00008;
  // Head-proxy supersampling per axis (its silhouette); the sub-pixel strands are anti-aliased
  // analytically (coverage = projected width x length).
  int head_supersampling = 3;
  // Sparse points sampled per view before the >= 2-view visibility test.
  int sparse_samples_per_view = 400;

  template <typename Visitor>
  void ForEachField(Visitor&& v) {
    v("output_path", &output_path, "folder to write dense/ and gt/ into");
    v("style", &style, "straight or curly");
    v("rig", &rig, "gantry (T groups of 4) or handheld (true poses either way)");
    v("num_groups", &num_groups, "gantry: number of T groups (1..8)");
    v("num_views", &num_views, "handheld: number of views (0 = 4 * num_groups)");
    v("width", &width, "image width in pixels (height = 2/3 width)");
    v("seed", &seed, "random seed (same seed, same bytes)");
    v("num_strands", &num_strands, "number of hair strands");
    v("strands_path", &strands_path,
      "render the strands of this folder (strands_points.npy, strands_offsets.npy: a data "
      "set's gt/) instead of generating them");
    v("hair_root_diameter_m", &hair_root_diameter_m, "strand diameter at the root (m)");
    v("hair_tip_diameter_m", &hair_tip_diameter_m, "strand diameter at the tip (m)");
    v("head_supersampling", &head_supersampling, "head/background samples per pixel axis");
    v("sparse_samples_per_view", &sparse_samples_per_view,
      "candidate sparse points sampled per view");
  }
  bool Check(std::string* error) const;
};

struct SynthesizeResult {
  int num_views = 0;
  int width = 0;
  int height = 0;
  int num_strands = 0;
  int num_strand_points = 0;
  int num_sparse_points = 0;
  double mean_track_length = 0;
  double hair_pixel_fraction = 0;  // hair-labelled pixels over all pixels, all views
  double seconds_hair = 0;
  double seconds_render = 0;
  double seconds_write = 0;
  double seconds_total = 0;
  std::string BriefReport() const;
};

// Generates the data set under options.output_path: dense/, gt/ and sparse/ (a text copy of
// the model), refused if any exists there already. They are written into a hidden folder of
// output_path and moved into place together once complete, so a run that throws leaves none of
// them. Throws hairmvs::Error for invalid options or unwritable paths.
SynthesizeResult RunSynthesize(const SynthesizeOptions& options);

}  // namespace hairmvs
