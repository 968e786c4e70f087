#include "hairmvs/synthesize.h"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "colmap_ext/reconstruction.h"
#include "colmap_ext/source_views.h"
#include "colmap_ext/workspace.h"
#include "src/core/depth_geometry.h"
#include "src/core/enum_names.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/progress.h"
#include "src/core/timer.h"
#include "src/evaluation/ground_truth.h"
#include "src/synthetic/camera_rig.h"
#include "src/synthetic/hair_model.h"
#include "src/synthetic/renderer.h"
#include "src/synthetic/sparse_points.h"

namespace hairmvs {
namespace {

// Spacing of the rendered tube pieces along the Catmull-Rom centrelines: the chord of a piece
// stays within ~20 um of the spline (straight hair bends over centimetres, curls over ~4 mm).
constexpr double kStraightDenseSpacingM = 0.002;
constexpr double kCurlyDenseSpacingM = 0.0008;

std::string Stem(const std::string& name) {
  const size_t dot = name.rfind('.');
  return dot == std::string::npos ? name : name.substr(0, dot);
}

cv::Mat RgbToBgrMat(const std::vector<uint8_t>& rgb, int width, int height) {
  cv::Mat mat(height, width, CV_8UC3);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const size_t p = (static_cast<size_t>(r) * width + c) * 3;
      mat.at<cv::Vec3b>(r, c) = cv::Vec3b(rgb[p + 2], rgb[p + 1], rgb[p]);
    }
  }
  return mat;
}

// Depth picture: nearer is brighter (40..255 over the view's depth range), background black.
cv::Mat DepthPicture(const FloatMap& depth) {
  float lo = std::numeric_limits<float>::max(), hi = 0.0f;
  for (float d : depth.Data()) {
    if (d > 0.0f) {
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  }
  cv::Mat mat(depth.Height(), depth.Width(), CV_8UC1, cv::Scalar(0));
  const float span = std::max(hi - lo, 1e-6f);
  for (int r = 0; r < depth.Height(); ++r) {
    for (int c = 0; c < depth.Width(); ++c) {
      const float d = depth.At(r, c);
      if (d > 0.0f) {
        mat.at<uint8_t>(r, c) = static_cast<uint8_t>(std::lround(40.0f + 215.0f * (hi - d) / span));
      }
    }
  }
  return mat;
}

// Labels: background black, skin orange-pink, hair yellow (as the shared sets' pictures).
cv::Mat LabelPicture(const std::vector<uint8_t>& label, int width, int height) {
  cv::Mat mat(height, width, CV_8UC3, cv::Scalar(0, 0, 0));
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const uint8_t l = label[static_cast<size_t>(r) * width + c];
      if (l == kLabelSkin) mat.at<cv::Vec3b>(r, c) = cv::Vec3b(120, 160, 230);
      if (l == kLabelHair) mat.at<cv::Vec3b>(r, c) = cv::Vec3b(0, 255, 255);
    }
  }
  return mat;
}

}  // namespace

namespace {

constexpr std::pair<HairStyle, const char*> kHairStyleNames[] = {
    {HairStyle::kStraight, "straight"}, {HairStyle::kCurly, "curly"}};
constexpr std::pair<CameraRigType, const char*> kCameraRigNames[] = {
    {CameraRigType::kGantry, "gantry"}, {CameraRigType::kHandheld, "handheld"}};

}  // namespace

std::string ToString(HairStyle style) { return EnumName(kHairStyleNames, style); }
bool FromString(const std::string& text, HairStyle* style) {
  return EnumFromName(kHairStyleNames, text, style);
}
std::string ToString(CameraRigType rig) { return EnumName(kCameraRigNames, rig); }
bool FromString(const std::string& text, CameraRigType* rig) {
  return EnumFromName(kCameraRigNames, text, rig);
}

bool SynthesizeOptions::Check(std::string* error) const {
  std::ostringstream e;
  if (output_path.empty()) e << "output_path must be given; ";
  if (num_groups < 1 || num_groups > 8) e << "num_groups must be in [1, 8]; ";
  if (num_views != 0 && (num_views < 2 || num_views > 100)) {
    e << "num_views must be 0 or in [2, 100]; ";
  }
  if (width < 32 || width > 8192) e << "width must be in [32, 8192]; ";
  // The seed is taken as unsigned: -1 would quietly be 2^64 - 1.
  if (seed < 0) e << "seed must be >= 0; ";
  if (num_strands < 1 || num_strands > 200000) e << "num_strands must be in [1, 200000]; ";
  if (!(hair_root_diameter_m > 0 && hair_root_diameter_m < 0.01)) {
    e << "hair_root_diameter_m must be in (0, 0.01); ";
  }
  if (!(hair_tip_diameter_m > 0 && hair_tip_diameter_m < 0.01)) {
    e << "hair_tip_diameter_m must be in (0, 0.01); ";
  }
  if (head_supersampling < 1 || head_supersampling > 16) {
    e << "head_supersampling must be in [1, 16]; ";
  }
  if (sparse_samples_per_view < 1) e << "sparse_samples_per_view must be >= 1; ";
  if (error != nullptr) *error = e.str();
  return e.str().empty();
}

std::string SynthesizeResult::BriefReport() const {
  std::ostringstream s;
  s << "Synthesized " << num_views << " views of " << width << " x " << height << " px, "
    << num_strands << " strands (" << num_strand_points << " points); " << num_sparse_points
    << " sparse points (mean track length " << mean_track_length << "); hair on "
    << 100.0 * hair_pixel_fraction << "% of the pixels.";
  return s.str();
}

SynthesizeResult RunSynthesize(const SynthesizeOptions& options) {
  std::string error;
  THROW_IF(!options.Check(&error), "synthesize: invalid options: " << error);
  Timer total_timer;
  SynthesizeResult result;
  // A set written over another would keep the old one's depth maps, fusion and truth beside the
  // new images; named before minutes of rendering.
  const std::vector<std::string> parts = {"dense", "gt", "sparse"};
  for (const std::string& part : parts) {
    const std::string path = JoinPaths(options.output_path, part);
    THROW_IF(Exists(path),
             "synthesize: " << path << " exists already: give a new --output_path (or remove "
                            << "the old set first)");
  }
  if (!options.strands_path.empty()) {
    RequireDir(options.strands_path, "strands folder (--strands_path: a data set's gt/)");
  }
  // The set is written into a hidden folder of output_path and its parts moved into place once
  // all are written: a run that fails (a full disk, a bad strands file) leaves no half set that
  // the next run would refuse.
  StagingDir staging(options.output_path, "synthesize");

  // Hair.
  Timer timer;
  const HeadModel head;
  HairGenerationOptions hair_options;
  hair_options.style = options.style;
  hair_options.num_strands = options.num_strands;
  hair_options.seed = static_cast<uint64_t>(options.seed);
  HairStrands hair;
  if (options.strands_path.empty()) {
    hair = GenerateHair(head, hair_options);
  } else {
    GroundTruthStrands given = ReadGroundTruthStrands(options.strands_path);
    THROW_IF(given.NumStrands() == 0,
             "synthesize: no strands in " << options.strands_path << " (strands_offsets.npy)");
    try {
      hair = HairFromStrands(head, std::move(given.points), std::move(given.offsets),
                             static_cast<uint64_t>(options.seed));
    } catch (const Error& e) {
      HAIRMVS_THROW("synthesize: the strands of " << options.strands_path << ": " << e.what());
    }
  }
  const Eigen::Vector3d hair_centre = hair.BoundingBoxCentre();
  DenseStrands dense = DensifyStrands(
      hair,
      options.style == HairStyle::kCurly ? kCurlyDenseSpacingM : kStraightDenseSpacingM,
      options.hair_root_diameter_m, options.hair_tip_diameter_m);
  result.num_strands = hair.NumStrands();
  result.num_strand_points = static_cast<int>(hair.points.size());
  result.seconds_hair = timer.ElapsedSeconds();

  // Cameras.
  const std::vector<SyntheticView> views =
      options.rig == CameraRigType::kGantry
          ? MakeGantryRig(options.num_groups, hair_centre, options.width)
          : MakeHandheldRig(options.num_views > 0 ? options.num_views : 4 * options.num_groups,
                            hair_centre, options.width, static_cast<uint64_t>(options.seed));
  const int W = views[0].width, H = views[0].height;
  result.num_views = static_cast<int>(views.size());
  result.width = W;
  result.height = H;

  const std::string dense_path = JoinPaths(staging.Path(), "dense");
  const std::string gt_path = JoinPaths(staging.Path(), "gt");
  for (const char* sub : {"images", "masks", "sparse", "stereo/depth_maps",
                          "stereo/normal_maps"}) {
    CreateDirs(JoinPaths(dense_path, sub));
  }
  CreateDirs(JoinPaths(gt_path, "vis"));

  RenderSettings settings;
  settings.head_supersampling = options.head_supersampling;
  HairScene scene(head, std::move(dense), hair.albedo, hair.layer, settings);

  // Render and write each view.
  std::vector<RenderedView> renders;
  renders.reserve(views.size());
  size_t hair_pixels = 0;
  Progress progress("synthesize", static_cast<int>(views.size()));
  for (size_t v = 0; v < views.size(); ++v) {
    progress.Start(static_cast<int>(v), views[v].name);
    timer.Restart();
    renders.push_back(scene.Render(views[v]));
    result.seconds_render += timer.ElapsedSeconds();
    timer.Restart();
    const RenderedView& r = renders.back();
    WriteImage(JoinPaths(dense_path, "images", views[v].name), RgbToBgrMat(r.rgb, W, H));
    cv::Mat mask(H, W, CV_8UC1, cv::Scalar(0));
    for (int row = 0; row < H; ++row) {
      for (int col = 0; col < W; ++col) {
        const size_t p = static_cast<size_t>(row) * W + col;
        // Foreground: a centre ray hit, or hair covering at least half the pixel.
        if (r.label[p] != kLabelBackground || r.hair_opacity[p] >= 0.5f) {
          mask.at<uint8_t>(row, col) = 255;
        }
        if (r.label[p] == kLabelHair) ++hair_pixels;
      }
    }
    WriteImage(JoinPaths(dense_path, "masks", views[v].name + ".png"), mask);
    GroundTruthView gt;
    gt.depth = r.depth;
    gt.label = r.label;
    WriteGroundTruthView(gt_path, views[v].name, gt);
    WriteImage(JoinPaths(gt_path, "vis", Stem(views[v].name) + "_depth.png"),
               DepthPicture(r.depth));
    WriteImage(JoinPaths(gt_path, "vis", Stem(views[v].name) + "_label.png"),
               LabelPicture(r.label, W, H));
    result.seconds_write += timer.ElapsedSeconds();
  }
  progress.Finish();
  result.hair_pixel_fraction =
      static_cast<double>(hair_pixels) / (static_cast<double>(W) * H * views.size());

  // The sparse model: true cameras and poses, points sampled on the visible surfaces.
  timer.Restart();
  Reconstruction model = MakeSparseModel(views, renders, options.sparse_samples_per_view,
                                         static_cast<uint64_t>(options.seed));
  result.num_sparse_points = static_cast<int>(model.points3D.size());
  size_t track_sum = 0;
  for (const auto& [id, point] : model.points3D) track_sum += point.track.size();
  result.mean_track_length =
      model.points3D.empty() ? 0.0 : static_cast<double>(track_sum) / model.points3D.size();
  WriteReconstruction(model, JoinPaths(dense_path, "sparse"), ModelFormat::kBinary);
  WriteReconstruction(model, JoinPaths(staging.Path(), "sparse"), ModelFormat::kText);

  // stereo/*.cfg as colmap image_undistorter writes them.
  std::vector<PatchMatchProblem> problems;
  std::vector<std::string> view_names;
  for (const auto& v : views) {
    PatchMatchProblem problem;
    problem.reference = v.name;
    problem.kind = PatchMatchProblem::Kind::kAuto;
    problem.num_auto = 20;
    problems.push_back(problem);
    view_names.push_back(v.name);
  }
  WritePatchMatchConfig(JoinPaths(dense_path, "stereo", "patch-match.cfg"), problems);
  WriteFusionConfig(JoinPaths(dense_path, "stereo", "fusion.cfg"), view_names);

  // gt/: cameras, strands, settings.
  GroundTruthCameras cameras;
  for (const auto& v : views) {
    cameras.names.push_back(v.name);
    cameras.R.push_back(v.R);
    cameras.t.push_back(v.t);
  }
  cameras.K = views[0].K;
  cameras.width = W;
  cameras.height = H;
  cameras.hair_centre = hair_centre;
  WriteGroundTruthCameras(gt_path, cameras);
  GroundTruthStrands strands;
  strands.points = hair.points;
  strands.offsets = hair.offsets;
  WriteGroundTruthStrands(gt_path, strands);

  // meta.json holds settings only (no times), so the same seed gives the same bytes.
  nlohmann::ordered_json meta;
  meta["generator"] = "hairmvs synthesize";
  meta["style"] = ToString(options.style);
  meta["colour"] = "darkbrown";
  meta["rig"] = ToString(options.rig);
  meta["seed"] = options.seed;
  meta["width"] = W;
  meta["height"] = H;
  meta["focal_px"] = views[0].K(0, 0);
  meta["head_supersampling"] = options.head_supersampling;
  meta["hair_centre"] = {hair_centre.x(), hair_centre.y(), hair_centre.z()};
  meta["n_strands"] = result.num_strands;
  if (!options.strands_path.empty()) meta["strands_path"] = options.strands_path;
  meta["n_points"] = result.num_strand_points;
  meta["hair_root_diameter_m"] = options.hair_root_diameter_m;
  meta["hair_tip_diameter_m"] = options.hair_tip_diameter_m;
  meta["head_semi_axes_m"] = {head.semi_axes.x(), head.semi_axes.y(), head.semi_axes.z()};
  meta["render_piece_spacing_m"] = options.style == HairStyle::kCurly ? kCurlyDenseSpacingM
                                                                      : kStraightDenseSpacingM;
  meta["n_sparse_points"] = result.num_sparse_points;
  nlohmann::ordered_json jviews = nlohmann::ordered_json::array();
  for (const auto& v : views) {
    jviews.push_back({{"name", v.name},
                      {"az_deg", v.az_deg},
                      {"el_deg", v.el_deg},
                      {"dist_m", v.dist_m},
                      {"roll_deg", v.roll_deg}});
  }
  meta["views"] = jviews;
  WriteFileAtomically(
      JoinPaths(gt_path, "meta.json"), [&](std::ostream& out) { out << meta.dump(1) << "\n"; },
      false);
  staging.Commit(parts);
  result.seconds_write += timer.ElapsedSeconds();
  result.seconds_total = total_timer.ElapsedSeconds();
  return result;
}

}  // namespace hairmvs
