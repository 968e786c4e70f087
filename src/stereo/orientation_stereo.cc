// The workspace side of orientation stereo: options, reading views, orientation fields (reused
// from stereo/orientation_maps/ or computed), source views and depth ranges, writing outputs.

#include "hairmvs/orientation_stereo.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <list>
#include <map>
#include <memory>
#include <optional>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <utility>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/source_views.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/orientation_fields.h"
#include "src/core/depth_geometry.h"
#include "src/core/enum_names.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/progress.h"
#include "src/mrf/mrf.h"
#include "src/opencl/opencl_context.h"
#include "src/opencl/opencl_error.h"
#include "src/orientation/orientation_field.h"
#include "src/orientation/orientation_maps.h"
#include "src/stereo/depth_estimator.h"
#include "src/stereo/consistency_filter.h"
#include "src/stereo/depth_range.h"

namespace hairmvs {

namespace {

struct ViewEstimate {
  DepthEstimate estimate;
  Eigen::Matrix3d K;  // the camera of the depth map's grid
};

// Where a view's depth is searched: the label range, and where each pixel's ray enters the
// masks' visual hull (the depth bound, the coarse labels' start and the strands' plane;
// EstimateDepthMap).
struct DepthSearch {
  double depth_min = 0;
  double depth_max = 0;  // 0: not computed yet
  std::string range_source;
  FloatMap visual_hull_entry;
  // The range is the visual hull's, searched in front of every sparse point: nothing bounds
  // its far end but the search, so the first estimate narrows it (DepthRangeOfEstimate).
  bool narrow_to_first_estimate = false;
};

// What the geometric pass would compute again for a view, kept from its first estimate: the
// depth search and the coarse stage's all-label volume (EstimateDepthMap), most of the work.
struct FirstEstimate {
  DepthSearch search;
  std::vector<float> coarse_volume;
  size_t Bytes() const {
    return sizeof(float) * (coarse_volume.size() + search.visual_hull_entry.Data().size());
  }
};

}  // namespace

namespace {

constexpr std::pair<StereoCost, const char*> kStereoCostNames[] = {
    {StereoCost::kOrientation, "orientation"},
    {StereoCost::kPhotometric, "photometric"},
    {StereoCost::kCombined, "combined"}};
constexpr std::pair<DepthSampling, const char*> kDepthSamplingNames[] = {
    {DepthSampling::kDepth, "depth"}, {DepthSampling::kInverseDepth, "inverse_depth"}};
constexpr std::pair<OrientationTransfer, const char*> kOrientationTransferNames[] = {
    {OrientationTransfer::kNone, "off"},
    {OrientationTransfer::kEpipoleRoll, "epipole_roll"},
    {OrientationTransfer::kPlaneHomography, "plane_homography"}};
constexpr std::pair<VisualHullBound, const char*> kVisualHullBoundNames[] = {
    {VisualHullBound::kOff, "off"},
    {VisualHullBound::kPenalty, "penalty"},
    {VisualHullBound::kFilter, "filter"}};

}  // namespace

std::string ToString(StereoCost cost) { return EnumName(kStereoCostNames, cost); }
bool FromString(const std::string& text, StereoCost* cost) {
  return EnumFromName(kStereoCostNames, text, cost);
}
std::string ToString(DepthSampling sampling) { return EnumName(kDepthSamplingNames, sampling); }
bool FromString(const std::string& text, DepthSampling* sampling) {
  return EnumFromName(kDepthSamplingNames, text, sampling);
}
std::string ToString(OrientationTransfer transfer) {
  return EnumName(kOrientationTransferNames, transfer);
}
bool FromString(const std::string& text, OrientationTransfer* transfer) {
  return EnumFromName(kOrientationTransferNames, text, transfer);
}
std::string ToString(VisualHullBound bound) { return EnumName(kVisualHullBoundNames, bound); }
bool FromString(const std::string& text, VisualHullBound* bound) {
  return EnumFromName(kVisualHullBoundNames, text, bound);
}

int OrientationStereoOptions::NumBestSources(int num_sources) const {
  // The small margin keeps, e.g., 2/3 of 3 sources at 2 despite rounding.
  return std::clamp(static_cast<int>(std::ceil(best_source_fraction * num_sources - 1e-9)), 1,
                    std::max(num_sources, 1));
}

std::vector<std::pair<StereoCost, float>> OrientationStereoOptions::DataTerms() const {
  if (cost != StereoCost::kCombined) return {{cost, 1.0f}};
  return {{StereoCost::kOrientation, static_cast<float>(1 - photometric_weight)},
          {StereoCost::kPhotometric, static_cast<float>(photometric_weight)}};
}

bool OrientationStereoOptions::StrandPlaneFromVisualHull() const {
  return strand_plane_from_visual_hull && MatchesOrientation() &&
         orientation_transfer == OrientationTransfer::kPlaneHomography;
}

int OrientationStereoOptions::WindowPx(int level) const {
  if (level <= 0) return window_px_level0;
  if (level == 1) return window_px_level1;
  return window_px_level2;
}

namespace {
// The largest lambda, given or scaled per view (ViewLambda): graph cuts loses double precision
// at weights of 1e15 and more, and float weights overflow beyond.
constexpr double kMaxLambda = 1e6;
}  // namespace

double OrientationStereoOptions::ViewLambda(double label_step_px) const {
  if (lambda_label_step_px <= 0 || !(label_step_px > 0)) return lambda;
  const double ratio = label_step_px / lambda_label_step_px;
  return std::min(lambda * ratio * ratio, kMaxLambda);
}

double OrientationStereoOptions::LevelSourceWeight(int level, int num_levels,
                                                   double view_angle_deg) const {
  if (level0_weight_angle_deg <= 0 || num_levels <= 1) return 1.0;
  // Coincident axes (a source beside the reference, looking the same way) take the largest
  // weight rather than a division by zero.
  constexpr double kMaxRatio = 4.0;
  const double ratio = view_angle_deg > 0
                           ? std::pow(level0_weight_angle_deg / view_angle_deg,
                                      level0_weight_angle_power)
                           : kMaxRatio;
  const double level0 = std::clamp(ratio, 1.0 / kMaxRatio, kMaxRatio);
  const double mean = (level0 + (num_levels - 1)) / num_levels;
  return (level == 0 ? level0 : 1.0) / mean;
}

bool OrientationStereoOptions::Check(std::string* error) const {
  std::ostringstream e;
  MrfSolverType solver;
  if (!IsValidMaxImageSize(max_image_size)) e << "max_image_size must be > 0 or -1; ";
  // -1 (COLMAP's "none given") or 0: from the sparse points; another negative value is a typo,
  // which colmap refuses too.
  if (depth_min < 0 && depth_min != -1) e << "depth_min must be > 0, or 0 or -1 (automatic); ";
  if (depth_max < 0 && depth_max != -1) e << "depth_max must be > 0, or 0 or -1 (automatic); ";
  if (depth_min > 0 && depth_max > 0 && depth_max <= depth_min) {
    e << "depth_max must exceed depth_min; ";
  }
  // Upper bounds on sizes and counts: an absurd value fails before any work, naming the
  // option, instead of running out of memory or time in the middle of a view.
  if (num_depths < 3 || num_depths > 4096) e << "num_depths must be in [3, 4096]; ";
  if (!(visual_hull_tolerance_m >= 0)) e << "visual_hull_tolerance_m must be >= 0; ";
  if (!(geom_consistency_max_error_px > 0)) e << "geom_consistency_max_error_px must be > 0; ";
  if (!(geom_consistency_min_triangulation_angle_deg >= 0 &&
        geom_consistency_min_triangulation_angle_deg < 90)) {
    e << "geom_consistency_min_triangulation_angle_deg must be in [0, 90); ";
  }
  // Upper bounds on weights (and a lower one on sigma_o): the MRF's costs are floats, which
  // overflow (or divide 0 by 0) long before a double does.
  if (!(geom_prior_weight >= 0 && geom_prior_weight <= 1e6)) {
    e << "geom_prior_weight must be in [0, 1e6]; ";
  }
  if (!(geom_prior_max_error_px > 0)) e << "geom_prior_max_error_px must be > 0; ";
  if (geom_consistency_iterations < 1) e << "geom_consistency_iterations must be >= 1; ";
  if (!(geom_consistency_max_view_angle_deg >= 0 && geom_consistency_max_view_angle_deg <= 180)) {
    e << "geom_consistency_max_view_angle_deg must be in [0, 180]; ";
  }
  if (geom_consistency_max_num_views < 0) e << "geom_consistency_max_num_views must be >= 0; ";
  if (!(geom_consistency_min_inconsistent_fraction >= 0 &&
        geom_consistency_min_inconsistent_fraction <= 1)) {
    e << "geom_consistency_min_inconsistent_fraction must be in [0, 1]; ";
  }
  if (!(geom_consistency_min_gain >= -1 && geom_consistency_min_gain <= 1)) {
    e << "geom_consistency_min_gain must be in [-1, 1]; ";
  }
  if (coarse_volume_cache_mib < 0) e << "coarse_volume_cache_mib must be >= 0; ";
  if (geom_consistency_min_views < 0) e << "geom_consistency_min_views must be >= 0; ";
  if (single_pass_type != "geometric" && single_pass_type != "photometric") {
    e << "single_pass_type must be geometric or photometric, not '" << single_pass_type << "'; ";
  }
  if (geom_consistency_only && !geom_consistency) {
    e << "geom_consistency_only needs geom_consistency; ";
  }
  if (geom_consistency_only && skip_existing) {
    // The first pass's jobs wrote .geometric maps too (filtered against the maps there were
    // then): existing ones cannot tell which views this pass did.
    e << "geom_consistency_only estimates every view given again from the .photometric maps; "
         "skip_existing would take the .geometric maps that the first pass wrote as done: run "
         "it without skip_existing; ";
  }
  if (visual_hull_mask_dilation_px < 0 || visual_hull_mask_dilation_px > 255) {
    e << "visual_hull_mask_dilation_px must be in [0, 255]; ";
  }
  if (visual_hull_min_carving_views < 1) e << "visual_hull_min_carving_views must be >= 1; ";
  if (num_levels < 1) e << "num_levels must be >= 1; ";
  if (!(max_strand_plane_tilt_deg >= 0 && max_strand_plane_tilt_deg < 90)) {
    e << "max_strand_plane_tilt_deg must be in [0, 90); ";
  }
  // Windows are centred on their pixel (radius window / 2): an even width would silently work
  // as the next odd one.
  for (const auto& [window, name] : {std::pair{window_px_level0, "window_px_level0"},
                                     std::pair{window_px_level1, "window_px_level1"},
                                     std::pair{window_px_level2, "window_px_level2"},
                                     std::pair{ncc_window_px, "ncc_window_px"}}) {
    if (window < 1 || window > 511 || window % 2 == 0) {
      e << name << " must be odd, in [1, 511] (a window centred on its pixel); ";
    }
  }
  if (!(guided_filter_eps > 0)) e << "guided_filter_eps must be > 0; ";
  if (orientation_normalization_radius_px < 0 || orientation_normalization_radius_px > 255) {
    e << "orientation_normalization_radius_px must be in [0, 255]; ";
  }
  // A window of one valid pixel (or of equal ones) has variance 0: eps is all that divides.
  if (!(orientation_normalization_eps > 0)) e << "orientation_normalization_eps must be > 0; ";
  if (!(min_confidence >= 0)) e << "min_confidence must be >= 0; ";
  // Beyond ~1e3 the guide's squares overflow float in the guided filter: every map empty.
  if (!(guide_rms >= 0 && guide_rms <= 1000)) e << "guide_rms must be in [0, 1000]; ";
  if (!(sigma_o >= 1e-6 && sigma_o <= 1e6)) e << "sigma_o must be in [1e-6, 1e6]; ";
  if (!(lambda >= 0 && lambda <= kMaxLambda)) e << "lambda must be in [0, 1e6]; ";
  if (!(lambda_label_step_px == 0 ||
        (lambda_label_step_px >= 0.01 && lambda_label_step_px <= 1e3))) {
    e << "lambda_label_step_px must be 0 or in [0.01, 1000]; ";
  }
  if (!FromString(mrf_solver, &solver)) e << "mrf_solver '" << mrf_solver << "' is unknown; ";
  if (mrf_max_cycles < 1) e << "mrf_max_cycles must be >= 1; ";
  if (mrf_icm_polish_iterations < 0) e << "mrf_icm_polish_iterations must be >= 0; ";
  if (coarse_level < -1) e << "coarse_level must be >= -1; ";
  // The orientation fields are computed with PyramidLevels() levels.
  if (PyramidLevels() > OrientationFieldOptions::kMaxLevels) {
    e << "num_levels and coarse_level + 1 must be at most " << OrientationFieldOptions::kMaxLevels
      << "; ";
  }
  if (coarse_first_level < 0) {
    e << "coarse_first_level must be >= 0; ";
  } else if (coarse_level > 0 && coarse_first_level > std::min(coarse_level, num_levels - 1)) {
    // Beyond them the coarse stage would quietly use level min(coarse_level, num_levels - 1).
    e << "coarse_first_level must be at most coarse_level and below num_levels; ";
  }
  if (!(level0_weight_angle_deg >= 0 && level0_weight_angle_deg < 180)) {
    e << "level0_weight_angle_deg must be in [0, 180); ";
  }
  if (!(level0_weight_angle_power > 0)) e << "level0_weight_angle_power must be > 0; ";
  if (fine_num_labels < 3 || fine_num_labels > 256) e << "fine_num_labels must be in [3, 256]; ";
  if (!(fine_label_step > 0)) {
    e << "fine_label_step must be > 0; ";
  } else if (const double band = (fine_num_labels - 1) * fine_label_step;
             coarse_level > 0 && band > num_depths - 1) {
    // The fine stage (coarse to fine only: coarse_level > 0) spans (fine_num_labels - 1) steps
    // from its first label; the whole range, num_depths - 1 steps of a coarse label.
    e << "the fine band ((fine_num_labels - 1) x fine_label_step = " << band
      << " coarse labels) must not span more than "
      << "the whole range (num_depths - 1 = " << num_depths - 1 << "): lower fine_num_labels "
      << "or fine_label_step, or raise num_depths; ";
  }
  if (slice_block < 1) e << "slice_block must be >= 1; ";
  if (!(photometric_weight >= 0 && photometric_weight <= 1)) {
    e << "photometric_weight must be in [0, 1]; ";
  }
  if (!(best_source_fraction > 0 && best_source_fraction <= 1)) {
    e << "best_source_fraction must be in (0, 1]; ";
  }
  *error = e.str();
  return error->empty();
}

OrientationFieldOptions OrientationStereoOptions::FieldOptions(
    const OrientationFieldOptions& filter) const {
  OrientationFieldOptions fields = filter;
  fields.num_levels = PyramidLevels();
  return fields;
}

std::string OrientationStereoResult::BriefReport() const {
  std::ostringstream out;
  out << "orientation_stereo: " << num_views << " depth maps";
  if (num_skipped > 0) out << " (" << num_skipped << " views skipped: their maps exist)";
  if (num_resumed_at_geometric_pass > 0) {
    out << " (" << num_resumed_at_geometric_pass
        << " views resumed at the geometric pass: their .photometric maps exist)";
  }
  if (geometric_rounds > 1) out << " (geometric pass in " << geometric_rounds << " rounds)";
  out << " in " << seconds << " s; peak memory " << peak_memory_mib << " MiB";
  return out.str();
}

namespace {

// Why a view's map may come out empty before any filter: the empty-map warning's words.
constexpr char kNoDepthEstimatedWhy[] =
    "no depth estimated: the depth range, the mask, min_confidence?";

void WriteDepthPng(const std::string& path, const FloatMap& depth) {
  std::vector<float> valid;
  for (float d : depth.Data()) {
    if (d > 0) valid.push_back(d);
  }
  float lo = 0, hi = 1;
  if (!valid.empty()) {
    std::sort(valid.begin(), valid.end());
    lo = valid[valid.size() * 2 / 100];
    hi = valid[valid.size() * 98 / 100];
    if (hi <= lo) hi = lo + 1e-6f;
  }
  cv::Mat gray(depth.Height(), depth.Width(), CV_8U);
  for (int row = 0; row < depth.Height(); ++row) {
    for (int col = 0; col < depth.Width(); ++col) {
      const float t = std::clamp((depth.At(row, col) - lo) / (hi - lo), 0.0f, 1.0f);
      gray.at<uint8_t>(row, col) = static_cast<uint8_t>(std::lround(255 * t));
    }
  }
  cv::Mat colour;
  cv::applyColorMap(gray, colour, cv::COLORMAP_JET);
  for (int row = 0; row < depth.Height(); ++row) {
    for (int col = 0; col < depth.Width(); ++col) {
      if (!(depth.At(row, col) > 0)) colour.at<cv::Vec3b>(row, col) = cv::Vec3b(0, 0, 0);
    }
  }
  WriteImage(path, colour);
}

void WriteNormalPng(const std::string& path, const FloatMap& normals) {
  cv::Mat colour(normals.Height(), normals.Width(), CV_8UC3);
  for (int row = 0; row < normals.Height(); ++row) {
    for (int col = 0; col < normals.Width(); ++col) {
      cv::Vec3b& px = colour.at<cv::Vec3b>(row, col);
      for (int c = 0; c < 3; ++c) {
        const float n = normals.At(row, col, c);
        // BGR order: blue = z, red = x.
        px[2 - c] = static_cast<uint8_t>(std::lround(127.5f * (std::clamp(n, -1.0f, 1.0f) + 1)));
      }
      if (normals.At(row, col, 2) == 0) px = cv::Vec3b(0, 0, 0);
    }
  }
  WriteImage(path, colour);
}

// Reads and caches the per-view data (camera, orientation pyramid, colour pyramid).
class ViewLoader {
 public:
  ViewLoader(const Workspace& workspace, const OrientationStereoOptions& options,
             const OrientationFieldOptions& field_options,
             std::shared_ptr<OpenCLContext> context, StageTimings* timings)
      : workspace_(workspace), options_(options), field_options_(field_options),
        context_(std::move(context)), timings_(timings) {}

  const StereoViewData& Load(const std::string& name) {
    for (auto it = cache_.begin(); it != cache_.end(); ++it) {
      if (it->first == name) {
        cache_.splice(cache_.begin(), cache_, it);
        return cache_.front().second;
      }
    }
    StereoViewData data = Read(name);
    cache_.emplace_front(name, std::move(data));
    // A reference and its sources, plus the next group's, stay in memory.
    while (cache_.size() > 12) cache_.pop_back();
    return cache_.front().second;
  }

  FloatMap Mask(const std::string& name, int width, int height) const {
    return ReadMask(workspace_.MaskPath(name), width, height);
  }

  // The camera at the processing resolution.
  StereoCamera ProcessingCamera(const std::string& name) const {
    return workspace_.ViewCamera(name).AtMaxImageSize(options_.max_image_size);
  }

  // Camera and mask at the processing resolution of every view that has a mask except
  // `exclude`, for the visual hull (masks read and dilated once, then cached).
  std::vector<std::pair<StereoCamera, FloatMap>> MaskedViews(const std::string& exclude) {
    if (masked_views_.empty()) {
      for (const std::string& name : workspace_.ImageNames()) {
        if (workspace_.MaskPath(name).empty()) continue;
        const StereoCamera camera = ProcessingCamera(name);
        FloatMap mask = Mask(name, camera.width, camera.height);
        const int radius = options_.visual_hull_mask_dilation_px;
        if (radius > 0) {
          cv::Mat wrapped(mask.Height(), mask.Width(), CV_32F, mask.Data().data());
          cv::dilate(wrapped, wrapped,
                     cv::getStructuringElement(cv::MORPH_ELLIPSE,
                                               cv::Size(2 * radius + 1, 2 * radius + 1)));
        }
        masked_views_.emplace_back(name, std::make_pair(camera, std::move(mask)));
      }
    }
    std::vector<std::pair<StereoCamera, FloatMap>> views;
    for (const auto& [name, view] : masked_views_) {
      if (name != exclude) views.push_back(view);
    }
    return views;
  }

 private:
  StereoViewData Read(const std::string& name) {
    ScopedStageTimer timer(timings_, "orientation");
    StereoViewData data;
    data.camera = ProcessingCamera(name);
    const int w = data.camera.width, h = data.camera.height;

    // The fields are those of the filter options in use at this size, whatever computed them.
    const OrientationFieldOptions field_options = options_.FieldOptions(field_options_);
    std::string provenance;
    if (options_.reuse_orientation_maps || options_.write_orientation_maps) {
      provenance = OrientationFieldsProvenance(workspace_, name, w, h, field_options);
    }
    std::optional<std::vector<FloatMap>> cached;
    if (options_.reuse_orientation_maps) {
      std::string why_not;
      cached = ReadCachedOrientationFields(workspace_, name, provenance, data.camera,
                                           options_.PyramidLevels(), &why_not);
      if (!why_not.empty()) LOG(INFO) << name << ": " << why_not << "; computing them again";
    }
    if (cached) {
      data.orientation = std::move(*cached);
    } else {
      if (!computer_) {
        computer_ = std::make_unique<OrientationFieldComputer>(context_, field_options);
      }
      // Under this stage's "orientation": the reading is not timed apart.
      data.orientation = ComputeViewOrientationFields(workspace_, name, options_.max_image_size,
                                                      computer_.get());
      if (options_.write_orientation_maps) {
        WriteOrientationFields(workspace_, name, provenance, data.orientation);
      }
    }
    if (options_.MatchesOrientation() && options_.orientation_normalization_radius_px > 0) {
      for (const FloatMap& level : data.orientation) {
        data.matching.push_back(NormalizeOrientationField(
            level, options_.orientation_normalization_radius_px,
            static_cast<float>(options_.orientation_normalization_eps)));
      }
    }
    if (options_.MatchesColour()) {
      data.rgb.push_back(workspace_.ReadViewRgb(name, options_.max_image_size));
      for (int l = 1; l < options_.PyramidLevels(); ++l) {
        data.rgb.push_back(DownsampleHalf(data.rgb.back()));
      }
    }
    return data;
  }

  const Workspace& workspace_;
  const OrientationStereoOptions& options_;
  const OrientationFieldOptions field_options_;
  std::shared_ptr<OpenCLContext> context_;
  StageTimings* timings_;
  std::unique_ptr<OrientationFieldComputer> computer_;
  std::list<std::pair<std::string, StereoViewData>> cache_;
  std::vector<std::pair<std::string, std::pair<StereoCamera, FloatMap>>> masked_views_;
};

// Whether the `type` (geometric or photometric) depth and normal maps of `name` exist.
// Whether `name`'s `type` depth and normal maps are there as whole Mats of 1 and 3 channels of
// one size, as skip_existing needs. A damaged one (cut short, another format: the writes are
// atomic, so not ours) counts as missing, with a warning, and is computed again.
bool HasDepthAndNormals(const Workspace& workspace, const std::string& name,
                        const std::string& type) {
  const std::string depth_path = workspace.DepthMapPath(name, type);
  const std::string normal_path = workspace.NormalMapPath(name, type);
  if (!ExistsFile(depth_path) || !ExistsFile(normal_path)) return false;
  try {
    const MatShape depth = ReadMatShape(depth_path);
    const MatShape normal = ReadMatShape(normal_path);
    THROW_IF(depth.channels != 1,
             depth_path << ": a depth map has 1 channel, not " << depth.channels);
    THROW_IF(normal.channels != 3 || normal.width != depth.width || normal.height != depth.height,
             normal_path << ": a normal map has 3 channels and its depth map's size");
  } catch (const Error& e) {
    LOG(WARNING) << e.what() << ": " << name << " is computed again";
    return false;
  }
  return true;
}

// Writes a depth map, its normal map and, with `png`, their pictures, as `type` (geometric or
// photometric) maps.
void WriteDepthAndNormals(const Workspace& workspace, const std::string& name,
                          const std::string& type, const FloatMap& depth,
                          const Eigen::Matrix3d& K, bool png) {
  const std::string depth_path = workspace.DepthMapPath(name, type);
  const std::string normal_path = workspace.NormalMapPath(name, type);
  const FloatMap normals = NormalMapFromDepthMap(depth, K);
  // The pair as one unit for a resumed run (HasDepthAndNormals): the depth map marks it whole,
  // so that a run stopped between the two renames leaves no depth map, and the view is computed
  // again, rather than a new depth map beside the old normals (or the reverse).
  WriteFilesAtomically({{normal_path, [&](std::ostream& out) { WriteMat(out, normals); }},
                        {depth_path, [&](std::ostream& out) { WriteMat(out, depth); }}},
                       /*last_marks_complete=*/true);
  if (png) {
    WriteDepthPng(depth_path + ".png", depth);
    WriteNormalPng(normal_path + ".png", normals);
  } else {
    // A picture of the map this one replaced (an earlier run's --write_png 1) would show other
    // depths: removed rather than left beside the new map.
    for (const std::string& picture : {depth_path + ".png", normal_path + ".png"}) {
      std::error_code ignored;
      std::filesystem::remove(picture, ignored);
    }
  }
}

// Removes a view's `type` depth map (first: it marks the pair whole), normal map and their
// pictures, where they exist.
void RemoveDepthAndNormals(const Workspace& workspace, const std::string& name,
                           const std::string& type) {
  const std::string depth_path = workspace.DepthMapPath(name, type);
  const std::string normal_path = workspace.NormalMapPath(name, type);
  for (const std::string& path :
       {depth_path, normal_path, depth_path + ".png", normal_path + ".png"}) {
    std::error_code ec;
    std::filesystem::remove(path, ec);
    THROW_IF(ec, "Cannot remove " << path << ": " << ec.message());
  }
}

// Warns of the sources whose match the stereo cannot trust, once per view (its first
// estimate): one that images the hair at a scale that none of its levels that the reference's
// levels meet matches, and, with the epipole roll, one whose epipole lies in the reference's
// image. Says which levels meet where a source is matched at other levels (match_source_scale).
void WarnOfMismatchedSources(const std::string& name, const StereoViewData& ref,
                             const std::vector<const StereoViewData*>& sources,
                             const std::vector<std::string>& source_names,
                             const DepthLabels& labels, const OrientationStereoOptions& options) {
  // The orientation fields' filters are in pixels: a source that images the hair at another
  // scale sees other strands' bands at the same level, and its depths lean behind (the README
  // measures it). Matched at other levels, one level that matches suffices: close-ups whose
  // finest level meets a source's level three times off still score well (the README's mixed
  // T groups). Level for level, synth_handheld's close-up h14 scored among its best views with
  // its sources at 0.56-0.65 times its scale: warned beyond 1.85 times.
  constexpr double kMaxImageScaleRatio = 1.85;
  const bool colour = options.MatchesColour();
  // The data term's levels, as EstimateDepthMap takes them.
  const int num_levels = std::min(options.num_levels, CommonPyramidLevels(ref, sources, colour));
  for (size_t s = 0; s < sources.size(); ++s) {
    const double ratio = SourceScaleRatio(ref, *sources[s], labels);
    const int offset = SourceLevelOffset(ratio, options.match_source_scale);
    const double mismatch =
        BestLevelScaleMismatch(*sources[s], ratio, offset, colour, num_levels);
    if (mismatch > kMaxImageScaleRatio) {
      LOG(WARNING) << name << ": source " << source_names[s] << " images the hair at "
                   << std::setprecision(3) << ratio << " times this view's scale (px per metre "
                   << "at " << labels.Depth(labels.MiddleLabel()) << " m), and the "
                   << "levels of it that this view's levels meet are at best " << mismatch
                   << " times off: orientation fields do not match across scales, so that its "
                      "depths lean behind; give the views closer scales (images of one size, "
                      "--OrientationStereo.max_image_size"
                   << (options.match_source_scale ? ""
                                                  : "; --OrientationStereo.match_source_scale 1")
                   << ") or other sources (stereo/patch-match.cfg)";
    } else if (offset != 0) {
      std::ostringstream levels;
      for (int l = 0; l < num_levels; ++l) {
        levels << (l > 0 ? ", " : "") << SourceLevel(*sources[s], l, offset, colour);
      }
      LOG(INFO) << name << ": source " << source_names[s] << " images the hair at "
                << std::setprecision(3) << ratio << " times this view's scale: its levels "
                << levels.str() << " meet this view's levels 0-" << num_levels - 1;
    }
    // Eq. 5's roll is one angle per pair, that of the epipole seen from the principal point:
    // where the epipole lies in the image (a source ahead or behind), the direction to it, and
    // so the roll, changes across the image.
    const Eigen::Vector3d src_center = sources[s]->camera.Center();
    if (options.orientation_transfer == OrientationTransfer::kEpipoleRoll &&
        EpipoleInImage(ref.camera, src_center)) {
      const Eigen::Vector2d e = Epipole(ref.camera, src_center).hnormalized();
      LOG(WARNING) << name << ": source " << source_names[s] << "'s epipole lies in the image, at ("
                   << e.x() << ", " << e.y() << ") px, where the epipole roll correction is no "
                   << "single angle: its orientation cost is wrong there; "
                      "--OrientationStereo.orientation_transfer plane_homography (the default) "
                      "carries each orientation itself";
    }
  }
}

}  // namespace

OrientationStereoResult RunOrientationStereo(const std::string& workspace_path,
                                             const std::vector<std::string>& image_names,
                                             const OrientationStereoOptions& options,
                                             StageTimings* timings,
                                             const std::string& device_spec,
                                             const SourceViewOptions* source_views,
                                             const OrientationFieldOptions* field_options) {
  Timer total_timer;
  std::string error;
  THROW_IF(!options.Check(&error), "invalid --OrientationStereo options: " << error);
  StageTimings local_timings;
  if (timings == nullptr) timings = &local_timings;
  const Workspace workspace = Workspace::Read(workspace_path, options.mask_path);
  std::vector<std::string> names = workspace.SelectImages(image_names);
  workspace.RequireUndistortedCameras();
  // A masks folder with missing masks is reported by Workspace::Read; no folder at all is the
  // state of a workspace fresh from colmap image_undistorter, which matches the whole scene.
  if (workspace.MaskFolder().empty()) {
    const std::string masks = JoinPaths(workspace_path, "masks");
    LOG(WARNING) << masks << (Exists(masks) ? " is no folder" : " does not exist")
                 << ": every pixel is matched, the background too, and each "
                    "depth range comes from all of the view's sparse points. With hair masks "
                    "(masks/<image name>.png, 255 = hair) the depth maps cover the hair only, "
                    "within the masks' visual hull";
  }

  const SourceViewOptions source_options =
      source_views != nullptr ? *source_views : SourceViewOptions();
  THROW_IF(!source_options.Check(&error), "invalid --SourceViews options: " << error);
  std::map<std::string, std::vector<std::string>> sources_of;
  for (const SourceViewSelection& selection : SelectSourceViews(workspace, source_options)) {
    sources_of[selection.reference] = selection.sources;
  }
  // A whole-workspace run that could write no map at all is an error, not "0 depth maps" and
  // rc 0. A subset's view without sources only warns: a job of a cluster array may get one.
  THROW_IF(image_names.empty() && std::none_of(names.begin(), names.end(),
                                               [&](const std::string& name) {
                                                 return sources_of.count(name) > 0 &&
                                                        !sources_of.at(name).empty();
                                               }),
           "No view of " << workspace_path << " has source views to match against ("
                         << (source_options.use_config
                                 ? "stereo/patch-match.cfg, where it exists, lists none; "
                                 : "")
                         << "no two views share sparse points of sparse/): no depth map can "
                            "be computed");

  std::shared_ptr<OpenCLContext> context = OpenCLContext::Create(device_spec);
  const OrientationFieldOptions fields =
      field_options != nullptr ? *field_options : OrientationFieldOptions();
  THROW_IF(!fields.Check(&error), "invalid --OrientationField options: " << error);
  // Outputs that cannot be written are found before minutes of work, not after; and only once
  // the options, the sources and the device hold, so that a run refused for those leaves no
  // empty folders in the workspace.
  for (const std::string& name : names) {
    RequireWritableDir(ParentPath(workspace.DepthMapPath(name)), "depth map folder");
    RequireWritableDir(ParentPath(workspace.NormalMapPath(name)), "normal map folder");
    RequireWritableDir(ParentPath(workspace.ConfidenceMapPath(name)), "confidence map folder");
    if (options.write_cost_volume) {
      RequireWritableDir(ParentPath(workspace.CostVolumePath(name)), "cost volume folder");
    }
  }
  ViewLoader loader(workspace, options, fields, context, timings);
  OrientationStereoResult result;
  // The views this run computes (all of `names` but those skip_existing finds done), those it
  // estimates first and those that start at the geometric pass.
  std::vector<std::string> to_run, to_estimate;
  std::set<std::string> resumed;
  const std::string final_type = options.FinalMapType();
  for (const std::string& name : names) {
    if (options.skip_existing && HasDepthAndNormals(workspace, name, final_type)) {
      std::printf("  %s: skipped: its .%s depth and normal maps exist (delete them to compute "
                  "it again)\n", name.c_str(), final_type.c_str());
      ++result.num_skipped;
      continue;
    }
    to_run.push_back(name);
    if (options.geom_consistency_only) continue;
    if (options.skip_existing && options.geom_consistency &&
        HasDepthAndNormals(workspace, name, "photometric")) {
      std::printf("  %s: its .photometric depth and normal maps exist: resumed at the "
                  "geometric pass\n", name.c_str());
      resumed.insert(name);
      ++result.num_resumed_at_geometric_pass;
      continue;
    }
    to_estimate.push_back(name);
  }
  std::fflush(stdout);
  std::set<std::string> estimated;  // views whose depth map was estimated in this run
  std::vector<std::string> empty_maps;  // views whose written map has no depth, with why
  auto warn_no_sources = [](const std::string& name) {
    LOG(WARNING) << name << ": no source views (stereo/patch-match.cfg, or no overlapping "
                 << "view); no depth map written";
  };
  Progress progress("orientation_stereo", static_cast<int>(to_estimate.size()));
  // One view's depth map, with the other views' maps as a prior in the geometric pass; nothing
  // when the view has no source views.
  auto estimate_view_unnamed = [&](const std::string& name, Progress* progress,
                                   const GeometricPrior* prior,
                                   FirstEstimate* cache) -> std::optional<ViewEstimate> {
    const auto it = sources_of.find(name);
    if (it == sources_of.end() || it->second.empty()) {
      warn_no_sources(name);
      return std::nullopt;
    }
    progress->Stage("orientation fields");
    const std::vector<std::string>& source_names = it->second;  // capped by SelectSourceViews
    // Copies: the cache may evict while loading the sources.
    const StereoViewData ref = loader.Load(name);
    std::vector<StereoViewData> source_data;
    for (const std::string& source : source_names) source_data.push_back(loader.Load(source));
    std::vector<const StereoViewData*> sources;
    for (const StereoViewData& s : source_data) sources.push_back(&s);

    const FloatMap mask =
        loader.Mask(name, ref.orientation[0].Width(), ref.orientation[0].Height());
    // Whether the view has a mask file (without one, `mask` keeps every pixel).
    const bool has_mask = !workspace.MaskPath(name).empty();
    // The depth range and the visual-hull bound, from the first estimate when the geometric
    // pass estimates the view again.
    DepthSearch computed;
    DepthSearch& search = cache != nullptr ? cache->search : computed;
    if (search.depth_max <= 0) {
      // The other views' masks, for the range and the bound: copied out of the loader once.
      std::vector<std::pair<StereoCamera, FloatMap>> masked_views;
      auto others = [&]() -> const std::vector<std::pair<StereoCamera, FloatMap>>& {
        if (masked_views.empty()) masked_views = loader.MaskedViews(name);
        return masked_views;
      };
      double depth_min = options.depth_min, depth_max = options.depth_max;
      std::string range_source = "options";
      if (depth_min <= 0 || depth_max <= 0) {
        const uint32_t image_id = workspace.ImageByName(name).image_id;
        // Without a mask file the view's mask is all ones: every point counts, as COLMAP's rule.
        const DepthRange range = options.depth_range_from_mask && has_mask
                                     ? ComputeDepthRange(workspace.Model(), image_id, mask)
                                     : ComputeDepthRange(workspace.Model(), image_id);
        if (depth_min <= 0) depth_min = range.min_m;
        if (depth_max <= 0) depth_max = range.max_m;
        range_source = range.inside_mask ? "sparse in mask" : "sparse";
        // The masks' visual hull: the sparse points of a textured room say little about the
        // head, and those in the mask may be wrong too.
        VisualHullRangeOptions hull_options;
        hull_options.min_carving_views = options.visual_hull_min_carving_views;
        double hull_min = 0, hull_max = 0;
        HullRangeSource hull_source = HullRangeSource::kHull;
        if (options.depth_range_from_visual_hull && has_mask &&
            HullAndPointsDepthRange(ref.camera, mask, others(),
                                    // Without points in the mask, `range` has all of them.
                                    range.inside_mask
                                        ? ComputeDepthRange(workspace.Model(), image_id)
                                        : range,
                                    range, &hull_min, &hull_max, &hull_source, hull_options)) {
          range_source = hull_source == HullRangeSource::kPointsWithinHull
                             ? "visual hull and sparse points in mask"
                         : hull_source == HullRangeSource::kHullInFrontOfPoints
                             ? "visual hull, in front of the sparse points"
                             : "visual hull";
          if (hull_source == HullRangeSource::kHullInFrontOfPoints) {
            LOG(WARNING) << name << ": the masks' visual hull begins in front of every sparse "
                         << "point of this view (the hull from " << hull_min
                         << " m, the points from " << range.min_m
                         << " m): the automatic depth bounds are the hull's. Points on the "
                            "room alone, none on the head, do that; so do points or poses that "
                            "are wrong. Check the sparse model, or give "
                            "--OrientationStereo.depth_min and depth_max";
          }
          if (options.depth_min <= 0) depth_min = hull_min;
          if (options.depth_max <= 0) depth_max = hull_max;
          search.narrow_to_first_estimate =
              hull_source == HullRangeSource::kHullInFrontOfPoints && options.depth_min <= 0 &&
              options.depth_max <= 0;
        }
      }
      // One bound given and the other computed can cross; say which is which.
      THROW_IF((options.depth_min > 0) != (options.depth_max > 0) && depth_min > 0 &&
                   depth_max > 0 && !(depth_max > depth_min),
               name << ": the depth range is empty: " << depth_min << " to " << depth_max
                    << " m, " << (options.depth_min > 0 ? "depth_min" : "depth_max")
                    << " given and the other bound from the " << range_source
                    << "; give both bounds, or one on the other side");
      THROW_IF(!(depth_min > 0 && depth_max > depth_min),
               name << ": no depth range (too few sparse points seen by this view?); give "
                    << "--OrientationStereo.depth_min and depth_max");
      // Per pixel, where its ray enters the visual hull: a lower bound on its depth, where its
      // coarse labels start, and the surface whose tilt the strands' plane takes.
      if ((options.visual_hull_depth_bound != VisualHullBound::kOff ||
           options.StrandPlaneFromVisualHull() || options.coarse_labels_from_visual_hull) &&
          has_mask) {
        ScopedStageTimer timer(timings, "visual hull");
        VisualHullRangeOptions every_pixel_entries;
        every_pixel_entries.pixel_step = 1;
        every_pixel_entries.find_far_ends = false;  // only the entry bounds the depth
        every_pixel_entries.min_carving_views = options.visual_hull_min_carving_views;
        const FloatMap intervals =
            VisualHullIntervals(ref.camera, mask, others(), 0.5 * depth_min,
                                2 * depth_max, every_pixel_entries);
        search.visual_hull_entry = FloatMap(intervals.Width(), intervals.Height(), 1);
        std::copy_n(intervals.Channel(0), intervals.NumPixels(),
                    search.visual_hull_entry.Data().begin());
      }
      search.depth_min = depth_min;
      search.depth_max = depth_max;
      search.range_source = range_source;
    }
    const bool inverse = options.depth_sampling == DepthSampling::kInverseDepth;
    if (prior == nullptr) {
      WarnOfMismatchedSources(
          name, ref, sources, source_names,
          DepthLabels(search.depth_min, search.depth_max, options.num_depths, inverse), options);
    }
    auto estimate_in_range = [&] {
      const DepthLabels labels(search.depth_min, search.depth_max, options.num_depths, inverse);
      return EstimateDepthMap(context.get(), ref, sources, mask, search.visual_hull_entry,
                              labels, options, timings, progress, prior,
                              cache != nullptr ? &cache->coarse_volume : nullptr);
    };
    // A hull searched in front of every point runs far behind the head (a T group's cones meet
    // along the line of sight), and its labels are coarse: the range is narrowed to the first
    // estimate's depths, a fifth wider either way, and the first estimate made again. (The 240
    // px T group whose sparse points lie on the room only, README: 21.5 -> 7.1 mm.) The
    // geometric pass keeps that range where it kept the first estimate's search; where it
    // computes the range again (past coarse_volume_cache_mib, or geom_consistency_only), it
    // narrows it to the view's .photometric map, the first estimate made in the narrowed range.
    constexpr double kFirstEstimateMargin = 1.2;
    constexpr int kMinDepthsToNarrow = 100;  // fewer make noisy percentiles
    auto narrow_to = [&](const FloatMap& first_estimate, const char* what) {
      double narrowed_min = 0, narrowed_max = 0;
      if (!DepthRangeOfEstimate(first_estimate, kFirstEstimateMargin, kMinDepthsToNarrow,
                                &narrowed_min, &narrowed_max)) {
        return false;
      }
      narrowed_min = std::max(narrowed_min, search.depth_min);
      narrowed_max = std::min(narrowed_max, search.depth_max);
      if (!(narrowed_max > narrowed_min)) return false;
      std::printf("  %s: depth %.4f-%.4f m narrowed to %s, %.4f-%.4f m\n", name.c_str(),
                  search.depth_min, search.depth_max, what, narrowed_min, narrowed_max);
      search.depth_min = narrowed_min;
      search.depth_max = narrowed_max;
      search.range_source += ", narrowed to the first estimate";
      search.narrow_to_first_estimate = false;
      return true;
    };
    if (search.narrow_to_first_estimate && prior != nullptr) {
      const std::string photometric = workspace.DepthMapPath(name, "photometric");
      if (ExistsFile(photometric)) narrow_to(ReadMat(photometric), "its .photometric map's depths");
    }
    DepthEstimate estimate = estimate_in_range();
    if (search.narrow_to_first_estimate && prior == nullptr &&
        narrow_to(estimate.depth, "the first estimate's depths (estimated again)")) {
      if (cache != nullptr) cache->coarse_volume.clear();  // the wider range's
      estimate = estimate_in_range();
    }
    const double depth_min = search.depth_min, depth_max = search.depth_max;

    // The prior's maps: the sources' and those of the views looking the same way.
    const std::string prior_maps =
        prior != nullptr ? ", a prior from " + std::to_string(prior->views.size()) + " depth maps"
                         : "";
    std::printf("  %s: %d x %d, depth %.4f-%.4f m (%s), %d sources%s, %.3g px per label and "
                "radian, lambda %.4g, %d valid pixels (of the %s's %d, %d at the range's near "
                "end and %d at its far end), MRF energy %.4g (coarse) %.4g (fine)\n",
                name.c_str(), estimate.depth.Width(), estimate.depth.Height(), depth_min,
                depth_max, search.range_source.c_str(), static_cast<int>(sources.size()),
                prior_maps.c_str(), estimate.label_step_px, estimate.lambda,
                estimate.num_valid, has_mask ? "mask" : "image", estimate.num_in_mask,
                estimate.num_at_near_end, estimate.num_at_far_end, estimate.coarse_energy,
                estimate.fine_energy);
    std::fflush(stdout);
    // Hair at the range's ends lies outside it: a range that cuts the hair off. Said of the
    // first estimate (the geometric pass keeps its range), where a mask says what is hair:
    // without one, the background may lie beyond any range.
    constexpr double kMaxFractionOutsideRange = 0.01;
    const int num_near = estimate.num_at_near_end, num_far = estimate.num_at_far_end;
    if (prior == nullptr && has_mask && estimate.num_in_mask > 0 &&
        num_near + num_far > kMaxFractionOutsideRange * estimate.num_in_mask) {
      // Each end with where its bound came from: given, or the computed range's source.
      const bool near_given = options.depth_min > 0, far_given = options.depth_max > 0;
      std::ostringstream ends;
      ends << std::fixed << std::setprecision(4);
      if (num_near > 0) {
        ends << num_near << " its near end, " << depth_min << " m ("
             << (near_given ? "depth_min given" : search.range_source) << ")";
      }
      if (num_near > 0 && num_far > 0) ends << ", and ";
      if (num_far > 0) {
        ends << num_far << " its far end, " << depth_max << " m ("
             << (far_given ? "depth_max given" : search.range_source) << ")";
      }
      std::string advice;
      if ((num_near > 0 && near_given) || (num_far > 0 && far_given)) {
        advice = "move the depth bound given";
      }
      if ((num_near > 0 && !near_given) || (num_far > 0 && !far_given)) {
        advice += std::string(advice.empty() ? "" : "; ") +
                  "check the masks (one that misses hair carves it off the visual hull) and "
                  "the sparse points, or give the depth bounds (depth_min, depth_max)";
      }
      LOG(WARNING) << name << ": " << num_near + num_far << " of the mask's "
                   << estimate.num_in_mask << " pixels reach the ends of the depth range: "
                   << ends.str() << ". The range may cut the hair off: " << advice;
    }
    return ViewEstimate{std::move(estimate), ref.camera.K};
  };
  // The same, with the view and stage named in an error that does not name the view: a failed
  // OpenCL call, a buffer beyond the device's limit or memory that ran out, which can strike
  // anywhere.
  auto estimate_view = [&](const std::string& name, Progress* progress,
                           const GeometricPrior* prior,
                           FirstEstimate* cache) -> std::optional<ViewEstimate> {
    try {
      return estimate_view_unnamed(name, progress, prior, cache);
    } catch (const std::exception& e) {
      HAIRMVS_THROW(DescribeExceptionWithin(name, progress->Where(), e));
    }
  };
  // What the geometric pass would compute again, per view, within the memory budget.
  std::map<std::string, FirstEstimate> first_estimates;
  size_t first_estimate_bytes = 0;
  for (size_t i = 0; i < to_estimate.size(); ++i) {
    const std::string& name = to_estimate[i];
    progress.Start(static_cast<int>(i), name);
    FirstEstimate* cache = nullptr;
    if (options.geom_consistency && options.geom_prior_weight > 0 &&
        first_estimate_bytes < static_cast<size_t>(options.coarse_volume_cache_mib) << 20) {
      cache = &first_estimates[name];
    }
    const std::optional<ViewEstimate> view = estimate_view(name, &progress, nullptr, cache);
    if (cache != nullptr) first_estimate_bytes += cache->Bytes();
    if (!view) continue;
    progress.Stage("writing");
    {
      ScopedStageTimer timer(timings, "writing");
      // A .geometric map of an earlier run came from other .photometric maps than the one
      // written now: kept, it would let a resumed run (skip_existing) take the view as done.
      if (options.geom_consistency) RemoveDepthAndNormals(workspace, name, final_type);
      WriteDepthAndNormals(workspace, name, options.geom_consistency ? "photometric" : final_type,
                           view->estimate.depth, view->K, options.write_png);
      WriteMat(workspace.ConfidenceMapPath(name), view->estimate.confidence);
      if (options.write_cost_volume) {
        WriteCostVolume(workspace.CostVolumePath(name), workspace.CostVolumeDepthsPath(name),
                        view->estimate.coarse_data_term);
      }
    }
    estimated.insert(name);
    if (!options.geom_consistency) {
      result.depth_map_paths.push_back(workspace.DepthMapPath(name, final_type));
      ++result.num_views;
      if (view->estimate.num_valid == 0) {
        empty_maps.push_back(name + " (" + kNoDepthEstimatedWhy + ")");
      }
    }
  }
  progress.Finish();

  if (options.geom_consistency) {
    // The geometric pass: every view estimated now or resumed here (or, with
    // geom_consistency_only, every requested view) is estimated again with its sources' maps
    // (and those of the views looking the same way, below) as a prior, in rounds (each from the
    // previous round's maps of every view, the .photometric ones first, so that the order of
    // the views does not matter), and its final map filtered by consistency with the
    // maps its prior came from (as COLMAP's geometric pass filters against the maps it reads:
    // with one round, a job of an array gives the map one process would).
    std::vector<std::string> to_filter;  // in the order of `names`
    for (const std::string& name : to_run) {
      if (sources_of.count(name) == 0) {  // never estimated: the first pass said so
        if (options.geom_consistency_only) warn_no_sources(name);
        continue;
      }
      if (options.geom_consistency_only || estimated.count(name) > 0 || resumed.count(name) > 0) {
        to_filter.push_back(name);
      }
    }
    // Each view's latest map but the last round's: its .photometric map (read once), then
    // each round's estimate. Held cropped to their depths (FusionView::CropToDepth), as are the
    // filtered maps and the confidences below (CroppedFloatMap), whole only as they are
    // written: a large workspace's maps are all held at once.
    std::map<std::string, FusionView> latest;
    // The last round's estimates, filtered against the maps their prior came from.
    struct FilteredMap {
      CroppedFloatMap depth;
      Eigen::Matrix3d K;
      ConsistencyFilterStats stats;
    };
    std::map<std::string, FilteredMap> final_maps;
    // The views whose maps a view's prior and filter read: its sources and, within
    // geom_consistency_max_view_angle_deg, the other views of this run looking the same way
    // (of this run: so that a job of an array, given its own views, reads no map that another
    // job may or may not have written yet; with geom_consistency_only, of the workspace, whose
    // .photometric maps are all written by then, so that a job of that pass reads what one
    // process would). Views without sources of their own (a
    // patch-match.cfg listing only some references) never have a map: they are matched
    // against, not read.
    std::map<std::string, std::vector<std::string>> consistency_views_of;
    for (const auto& [name, sources] : sources_of) {
      std::vector<std::string>& views = consistency_views_of[name];
      for (const std::string& source : sources) {
        if (sources_of.count(source) > 0) views.push_back(source);
      }
    }
    if (options.geom_consistency_max_view_angle_deg > 0) {
      const std::set<std::string> in_run(names.begin(), names.end());
      for (const std::string& name : to_filter) {
        std::vector<std::string>& views = consistency_views_of[name];
        std::vector<std::string> same_way;
        for (std::string& other : ViewsLookingTheSameWay(
                 workspace, name, views, options.geom_consistency_max_view_angle_deg)) {
          if ((options.geom_consistency_only || in_run.count(other) > 0) &&
              sources_of.count(other) > 0) {
            same_way.push_back(std::move(other));
          }
        }
        // The nearest in direction, so that a large workspace's prior and filter read a bounded
        // number of maps per view (each such view's map sits in the prior's device buffer).
        for (std::string& other : NearestInDirection(
                 workspace, name, same_way,
                 static_cast<size_t>(options.geom_consistency_max_num_views))) {
          views.push_back(std::move(other));
        }
      }
    }
    auto load = [&](const std::string& name) -> const FusionView* {
      auto it = latest.find(name);
      if (it == latest.end()) {
        FusionView view;
        const std::string path = workspace.DepthMapPath(name, "photometric");
        if (ExistsFile(path)) {
          const StereoCamera camera = loader.ProcessingCamera(name);
          view.name = name;
          view.depth = ReadMat(path);
          THROW_IF(view.depth.Channels() != 1,
                   path << ": not a depth map (" << view.depth.Channels() << " channels)");
          view.K = camera.ScaledToMap(view.depth.Width(), view.depth.Height(), path).K;
          view.R = camera.R;
          view.t = camera.t;
          view.CropToDepth();
        }
        it = latest.emplace(name, std::move(view)).first;
      }
      return it->second.depth.Empty() ? nullptr : &it->second;
    };
    // A view's latest map and those of the views it is checked against that have one (of
    // num_others).
    struct ViewMaps {
      const FusionView* ref = nullptr;
      std::vector<const FusionView*> others;
      size_t num_others = 0;
    };
    auto maps_of = [&](const std::string& name) {
      ViewMaps maps;
      maps.ref = load(name);
      THROW_IF(maps.ref == nullptr, workspace.DepthMapPath(name, "photometric")
                                        << ": missing; run orientation_stereo on " << name
                                        << " first (without geom_consistency_only); or "
                                           "another process is replacing its maps (a view in "
                                           "two jobs at once)");
      const auto it = consistency_views_of.find(name);
      if (it != consistency_views_of.end()) {
        maps.num_others = it->second.size();
        for (const std::string& other : it->second) {
          if (const FusionView* view = load(other)) maps.others.push_back(view);
        }
      }
      return maps;
    };
    // Up to geom_consistency_iterations rounds; each round's maps are filtered against the maps
    // their prior came from, and the pass stops where nearly all of them agree or where the
    // round added little agreement (see the options): the last round's filtered maps are the
    // .geometric ones.
    const int max_rounds =
        options.geom_prior_weight > 0 ? options.geom_consistency_iterations : 0;
    double previous_consistent = -1;  // the previous round's fraction of consistent depths
    for (int round = 0; round < max_rounds; ++round) {
      const bool last_possible_round = round + 1 == max_rounds;
      std::ostringstream task;
      task << "geometric consistency";
      if (max_rounds > 1) task << ", round " << round + 1 << " of at most " << max_rounds;
      Progress round_progress(task.str(), static_cast<int>(to_filter.size()));
      std::map<std::string, FusionView> next;
      std::map<std::string, CroppedFloatMap> confidences;
      for (size_t i = 0; i < to_filter.size(); ++i) {
        const std::string& name = to_filter[i];
        round_progress.Start(static_cast<int>(i), name);
        const ViewMaps maps = maps_of(name);
        // Without all of those maps (a job array's other jobs), the prior would depend on which
        // are done: such a view is only filtered (the filter below says so).
        if (maps.others.empty() || maps.others.size() < maps.num_others) continue;
        // COLMAP's geometric pass: estimated again with those maps as a prior.
        GeometricPrior prior;
        prior.views = maps.others;
        prior.weight = options.geom_prior_weight;
        prior.max_error_px = options.geom_prior_max_error_px;
        const auto cached = first_estimates.find(name);
        FirstEstimate* cache = cached != first_estimates.end() ? &cached->second : nullptr;
        // The estimate takes the cached volume: a round that may not be the last gets a copy.
        FirstEstimate copy;
        if (cache != nullptr && !last_possible_round) {
          copy = *cache;
          cache = &copy;
        }
        if (std::optional<ViewEstimate> view =
                estimate_view(name, &round_progress, &prior, cache)) {
          FusionView estimate;
          estimate.name = name;
          estimate.R = maps.ref->R;
          estimate.t = maps.ref->t;
          estimate.K = view->K;
          estimate.depth = std::move(view->estimate.depth);
          estimate.CropToDepth();
          next.emplace(name, std::move(estimate));
          confidences[name] = CroppedFloatMap::AbovePositive(view->estimate.confidence);
        }
        if (last_possible_round) first_estimates.erase(name);
      }
      round_progress.Finish();
      ++result.geometric_rounds;
      // Only the filtered depths: the unfiltered estimates are the next round's prior.
      std::map<std::string, FilteredMap> filtered;
      ConsistencyFilterStats total;
      {
        ScopedStageTimer timer(timings, "consistency");
        for (const auto& [name, estimate] : next) {
          FilteredMap& map = filtered[name];
          map.depth = estimate.Part(FilterDepthMapByConsistency(
              estimate, maps_of(name).others, options.geom_consistency_max_error_px,
              options.geom_consistency_min_views,
              options.geom_consistency_min_triangulation_angle_deg, &map.stats));
          map.K = estimate.K;
          total.num_checked += map.stats.num_checked;
          total.num_kept += map.stats.num_kept;
        }
      }
      const double consistent =
          total.num_checked > 0 ? static_cast<double>(total.num_kept) / total.num_checked : 1;
      const bool last_round =
          last_possible_round ||
          1 - consistent < options.geom_consistency_min_inconsistent_fraction ||
          (previous_consistent >= 0 &&
           consistent - previous_consistent < options.geom_consistency_min_gain);
      if (total.num_checked > 0) {
        std::printf("  round %d: %.1f%% of %lld depths consistent with the previous maps%s\n",
                    round + 1, 100 * consistent, static_cast<long long>(total.num_checked),
                    last_round ? ": the last round" : ": another round");
      } else {
        // With no view estimated again, every view lacked some of the maps it is checked
        // against (another job's, not written yet): the filter below says so per view.
        std::printf("  round %d: no depths checked (%s)%s\n", round + 1,
                    next.empty() ? "no view has all the maps it is checked against"
                                 : "the estimates hold no depth",
                    last_round ? ": the last round" : ": another round");
      }
      previous_consistent = consistent;
      if (last_round) {
        // The confidence of the maps that are written as .geometric.
        for (const auto& [name, confidence] : confidences) {
          WriteMat(workspace.ConfidenceMapPath(name), confidence.Whole());
        }
        final_maps = std::move(filtered);
        break;
      }
      for (auto& [name, view] : next) latest[name] = std::move(view);
    }
    first_estimates.clear();

    // Why waiting for the other views may not help: said with the advice to run again.
    constexpr const char* kNoMapWhy =
        "a view that is no reference of stereo/patch-match.cfg never gets a map";
    Progress filter_progress("consistency filter", static_cast<int>(to_filter.size()));
    for (size_t i = 0; i < to_filter.size(); ++i) {
      const std::string& name = to_filter[i];
      filter_progress.Start(static_cast<int>(i), name);
      const ViewMaps maps = maps_of(name);
      const std::vector<const FusionView*>& others = maps.others;
      const auto estimated_again = final_maps.find(name);
      FloatMap depth;  // the .geometric map
      Eigen::Matrix3d K = maps.ref->K;
      ConsistencyFilterStats stats;  // of the filter that made it
      bool filtered = true;
      if (estimated_again != final_maps.end()) {  // filtered in its round
        depth = estimated_again->second.depth.Whole();
        estimated_again->second.depth = CroppedFloatMap();
        K = estimated_again->second.K;
        stats = estimated_again->second.stats;
      } else if (others.empty()) {
        LOG(WARNING) << name << ": none of the views it is checked against (its sources and "
                     << "the run's views looking the same way) has a .photometric depth map "
                     << "yet; its .geometric map is unfiltered (run again with "
                     << "--OrientationStereo.geom_consistency_only 1 once they have; " << kNoMapWhy
                     << ")";
        depth = maps.ref->Whole(maps.ref->depth);
        filtered = false;
      } else {
        if (max_rounds > 0 && others.size() < maps.num_others) {
          LOG(WARNING) << name << ": " << others.size() << " of the " << maps.num_others
                       << " views it is checked against have a .photometric depth map yet; its "
                       << ".geometric map is only filtered (run again with "
                       << "--OrientationStereo.geom_consistency_only 1 once they have; "
                       << kNoMapWhy << ")";
        }
        ScopedStageTimer timer(timings, "consistency");
        depth = maps.ref->Whole(FilterDepthMapByConsistency(
            *maps.ref, others, options.geom_consistency_max_error_px,
            options.geom_consistency_min_views,
            options.geom_consistency_min_triangulation_angle_deg, &stats));
      }
      if (filtered) {
        std::printf("  %s: %lld of %lld depths consistent with the maps of %d other view(s)\n",
                    name.c_str(), static_cast<long long>(stats.num_kept),
                    static_cast<long long>(stats.num_checked),
                    static_cast<int>(others.size()));
      }
      WriteDepthAndNormals(workspace, name, "geometric", depth, K, options.write_png);
      result.depth_map_paths.push_back(workspace.DepthMapPath(name, "geometric"));
      ++result.num_views;
      const bool empty = filtered ? stats.num_kept == 0
                                  : std::none_of(depth.Data().begin(), depth.Data().end(),
                                                 [](float d) { return d > 0; });
      if (empty) {
        empty_maps.push_back(
            filtered && stats.num_checked > 0
                ? name + " (none of its " + std::to_string(stats.num_checked) +
                      " depths agrees with geom_consistency_min_views " +
                      std::to_string(options.geom_consistency_min_views) +
                      " other maps within geom_consistency_max_error_px)"
                : name + " (" + kNoDepthEstimatedWhy + ")");
      }
    }
    filter_progress.Finish();
  }
  // colmap stereo_fusion reads stereo/fusion.cfg and aborts without one. A workspace from
  // colmap image_undistorter has it; one made otherwise gets what the undistorter writes:
  // every image of the model (fusion skips those without maps). Every job of an array writes
  // the same, atomically; the user's own is never replaced.
  const std::string fusion_cfg = JoinPaths(workspace.StereoPath(), "fusion.cfg");
  if (result.num_views > 0 && !Exists(fusion_cfg)) {
    WriteFusionConfig(fusion_cfg, workspace.ImageNames());
    LOG(INFO) << "Wrote " << fusion_cfg << " (every image, as colmap image_undistorter does), "
              << "which colmap stereo_fusion reads";
  }
  // A map left empty is written as such (COLMAP's filter writes them too), but never silently:
  // an option that removes everything would otherwise look like a finished run.
  if (!empty_maps.empty()) {
    LOG(WARNING) << empty_maps.size() << " of the " << result.num_views
                 << " depth maps written are empty: " << JoinStrings(empty_maps, "; ");
  }
  result.seconds = total_timer.ElapsedSeconds();
  result.peak_memory_mib = PeakResidentMemoryMiB();
  return result;
}

std::vector<ViewOutputs> WorkspaceOutputs(const std::string& workspace_path,
                                          const OrientationStereoOptions& options,
                                          const OrientationFieldOptions& field_options) {
  const Workspace workspace = Workspace::Read(workspace_path, options.mask_path);
  std::vector<ViewOutputs> outputs;
  for (const std::string& name : workspace.ImageNames()) {
    ViewOutputs view;
    view.name = name;
    const StereoCamera camera = workspace.ViewCamera(name).AtMaxImageSize(options.max_image_size);
    const std::string provenance =
        OrientationFieldsProvenance(workspace, name, camera.width, camera.height, field_options);
    if (CachedOrientationFieldsHold(workspace, name, provenance, camera, options.PyramidLevels(),
                                    &view.why_stale)) {
      view.fields = ViewOutputs::Fields::kUpToDate;
    } else if (!view.why_stale.empty()) {
      view.fields = ViewOutputs::Fields::kStale;
    }
    view.photometric_maps = HasDepthAndNormals(workspace, name, "photometric");
    view.geometric_maps = HasDepthAndNormals(workspace, name, "geometric");
    outputs.push_back(std::move(view));
  }
  return outputs;
}

}  // namespace hairmvs
