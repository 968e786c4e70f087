// EvaluateDataTerm: where the cheapest label of each coarse pixel lies against the true depth.

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/evaluation.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/progress.h"
#include "src/evaluation/evaluation_util.h"
#include "src/evaluation/ground_truth.h"

namespace hairmvs {
namespace {

// Per evaluated coarse pixel (one view's, or all views' pooled).
struct DataTermSamples {
  long num_outside_range = 0;
  std::vector<double> errors_m;        // cheapest label's depth - the true depth
  std::vector<double> label_errors;    // |cheapest label - true label position|
  std::vector<double> label_steps_m;   // depth step between the labels around the truth
  std::vector<double> true_depth_ranks;

  void Append(const DataTermSamples& other) {
    num_outside_range += other.num_outside_range;
    for (auto [to, from] : {std::pair(&errors_m, &other.errors_m),
                            std::pair(&label_errors, &other.label_errors),
                            std::pair(&label_steps_m, &other.label_steps_m),
                            std::pair(&true_depth_ranks, &other.true_depth_ranks)}) {
      to->insert(to->end(), from->begin(), from->end());
    }
  }
};

DataTermMetrics Summarize(const std::string& name, const DataTermSamples& samples) {
  DataTermMetrics m;
  m.name = name;
  const std::vector<double> abs_errors_m = Absolute(samples.errors_m);
  m.num_pixels = static_cast<long>(abs_errors_m.size());
  m.num_outside_range = samples.num_outside_range;
  m.label_step_mm = 1e3 * Percentile(samples.label_steps_m, 0.5);
  m.median_abs_error_mm = 1e3 * Percentile(abs_errors_m, 0.5);
  m.median_signed_error_mm = 1e3 * Percentile(samples.errors_m, 0.5);
  m.median_true_depth_rank = Percentile(samples.true_depth_ranks, 0.5);
  long n1 = 0, n5 = 0, n10 = 0;
  for (size_t i = 0; i < abs_errors_m.size(); ++i) {
    n1 += samples.label_errors[i] <= 1.0;
    n5 += abs_errors_m[i] <= 5e-3;
    n10 += abs_errors_m[i] <= 10e-3;
  }
  const double n = std::max<long>(1, m.num_pixels);
  m.within_1_label = n1 / n;
  m.within_5mm = n5 / n;
  m.within_10mm = n10 / n;
  return m;
}

nlohmann::json ToJson(const DataTermMetrics& m) {
  return {{"name", m.name},
          {"num_pixels", m.num_pixels},
          {"num_outside_range", m.num_outside_range},
          {"label_step_mm", m.label_step_mm},
          {"median_abs_error_mm", m.median_abs_error_mm},
          {"median_signed_error_mm", m.median_signed_error_mm},
          {"within_1_label", m.within_1_label},
          {"within_5mm", m.within_5mm},
          {"within_10mm", m.within_10mm},
          {"median_true_depth_rank", m.median_true_depth_rank}};
}

std::string TableRow(const DataTermMetrics& m) {
  char line[256];
  std::snprintf(line, sizeof(line),
                "%-14s %8ld %7ld %7.2f %8.2f %7.2f %6.1f%% %6.1f%% %6.1f%% %6.3f\n",
                m.name.c_str(), m.num_pixels, m.num_outside_range, m.label_step_mm,
                m.median_abs_error_mm, m.median_signed_error_mm, 100 * m.within_1_label,
                100 * m.within_5mm, 100 * m.within_10mm, m.median_true_depth_rank);
  return line;
}

// The fractional label position of `depth` among monotone `depths` (increasing or decreasing
// with the label); false when outside them.
bool LabelPosition(const std::vector<double>& depths, double depth, double* position) {
  for (size_t k = 0; k + 1 < depths.size(); ++k) {
    const double lo = std::min(depths[k], depths[k + 1]);
    const double hi = std::max(depths[k], depths[k + 1]);
    if (depth >= lo && depth <= hi) {
      *position = k + (depth - depths[k]) / (depths[k + 1] - depths[k]);
      return true;
    }
  }
  return false;
}

// The first pixel of a fine grid whose centre lies in pixel `coarse` of a grid `scale` times
// coarser over the same image, or beyond (SfM convention: the grids start at the same edge).
int FirstFinePixel(int coarse, double scale) {
  return static_cast<int>(std::ceil(coarse * scale - 0.5));
}

// The camera of a cost volume's grid: a level of the stereo's image pyramid
// (StereoCamera::PyramidLevel, whose image coordinates halve exactly, so that for an odd size
// the grid reaches past the image and is not the image scaled to the grid's size). The pyramid
// starts at `processing_camera`, the view's at the size the stereo ran at (its depth maps');
// for a volume of no level of it, the image scaled to the volume's size.
StereoCamera VolumeGridCamera(const StereoCamera& processing_camera, int width, int height,
                              const std::string& volume_path) {
  for (int level = 0; level < 16; ++level) {  // 2^16: past any image
    const StereoCamera grid = processing_camera.PyramidLevel(level);
    if (grid.width == width && grid.height == height) return grid;
  }
  return processing_camera.ScaledToMap(width, height, volume_path);
}

// The samples of one view: its volume against the true depths. Each true hair depth is
// back-projected with `truth_camera` (the camera the truth was rendered with, or the
// workspace's at the truth's size) and lands, as a z-depth in the workspace's camera of the
// volume's grid, in one coarse pixel: the true depths of a coarse pixel are those of the image
// pixels whose centres fall in it where the two cameras are the same. A coarse pixel covers
// scale_x x scale_y of the truth's pixels.
void EvaluateView(const CostVolume& volume, const GroundTruthView& gt,
                  const StereoCamera& truth_camera, const StereoCamera& grid_camera,
                  double scale_x, double scale_y, double min_hair_fraction,
                  DataTermSamples* samples) {
  const FloatMap& cost = volume.cost;
  const std::vector<double>& depths = volume.label_depths;
  const int cw = cost.Width(), ch = cost.Height(), num_labels = cost.Channels();
  const int gt_width = gt.depth.Width(), gt_height = gt.depth.Height();
  std::vector<std::vector<double>> cell_depths(static_cast<size_t>(cw) * ch);
  for (int gr = 0; gr < gt_height; ++gr) {
    for (int gc = 0; gc < gt_width; ++gc) {
      const float d = gt.depth.At(gr, gc);
      if (gt.label[static_cast<size_t>(gr) * gt_width + gc] != kLabelHair || !(d > 0)) continue;
      int c, r;
      double z;
      if (grid_camera.Project(truth_camera.BackProject(gc, gr, d), &c, &r, &z)) {
        cell_depths[static_cast<size_t>(r) * cw + c].push_back(z);
      }
    }
  }
  std::vector<float> costs(num_labels);
  for (int r = 0; r < ch; ++r) {
    // The image pixels whose centres fall into coarse pixel (r, c).
    const int row_begin = std::max(0, FirstFinePixel(r, scale_y));
    const int row_end = std::min(gt_height, FirstFinePixel(r + 1, scale_y));
    for (int c = 0; c < cw; ++c) {
      const int col_begin = std::max(0, FirstFinePixel(c, scale_x));
      const int col_end = std::min(gt_width, FirstFinePixel(c + 1, scale_x));
      const int covered = std::max(0, row_end - row_begin) * std::max(0, col_end - col_begin);
      const std::vector<double>& hair_depths = cell_depths[static_cast<size_t>(r) * cw + c];
      if (covered == 0 || hair_depths.empty() ||
          hair_depths.size() < min_hair_fraction * covered) {
        continue;
      }
      for (int k = 0; k < num_labels; ++k) costs[k] = cost.At(r, c, k);
      const auto [lo, hi] = std::minmax_element(costs.begin(), costs.end());
      if (!(*hi > *lo)) continue;  // no data term here (masked)
      const double true_depth = Percentile(hair_depths, 0.5);
      double position;
      if (!LabelPosition(depths, true_depth, &position)) {
        ++samples->num_outside_range;
        continue;
      }
      const int below = std::min(static_cast<int>(position), num_labels - 2);
      const double frac = position - below;
      const double true_cost = (1 - frac) * costs[below] + frac * costs[below + 1];
      const int cheapest = static_cast<int>(lo - costs.begin());
      samples->errors_m.push_back(depths[cheapest] - true_depth);
      samples->label_errors.push_back(std::abs(cheapest - position));
      samples->label_steps_m.push_back(std::abs(depths[below + 1] - depths[below]));
      const long cheaper = std::count_if(costs.begin(), costs.end(),
                                         [true_cost](float x) { return x < true_cost; });
      samples->true_depth_ranks.push_back(static_cast<double>(cheaper) / (num_labels - 1));
    }
  }
}

}  // namespace

bool DataTermEvaluationOptions::Check(std::string* error) const {
  if (!(min_hair_fraction > 0 && min_hair_fraction <= 1)) {
    *error = "--min_hair_fraction must be in (0, 1]";
    return false;
  }
  return CheckImageNames(image_names, error);
}

std::string DataTermEvaluationResult::Table() const {
  return EvaluationTable(
      "view             pixels outside step_mm  med_mm  sgn_mm  <=1lab  <=5mm <=10mm  rank\n",
      views, overall, json_path, TableRow);
}

DataTermEvaluationResult EvaluateDataTerm(const std::string& workspace_path,
                                          const std::string& ground_truth_path,
                                          const DataTermEvaluationOptions& options,
                                          StageTimings* timings) {
  std::string error;
  THROW_IF(!options.Check(&error), error);
  StageLaps laps(timings);
  const Workspace ws = Workspace::Read(workspace_path);
  const std::vector<std::string> names = ViewsToEvaluate(
      ws, options.image_names, [&](const std::string& name) { return ws.CostVolumePath(name); },
      "No cost volumes in " + JoinPaths(ws.StereoPath(), "cost_volumes") +
          " (run orientation_stereo with --OrientationStereo.write_cost_volume 1)");
  RequireOutputApartFromInputs(EvaluationFolder(ws, options.output_path), "--output_path",
                               ground_truth_path);
  const GroundTruthCameras true_cameras =
      ReadTrueCameras(ground_truth_path, options.in_true_cameras);

  DataTermEvaluationResult result;
  DataTermSamples pooled;
  Progress progress("evaluate_data_term", static_cast<int>(names.size()));
  for (size_t v = 0; v < names.size(); ++v) {
    const std::string& name = names[v];
    progress.Start(static_cast<int>(v), name);
    const CostVolume volume =
        ReadCostVolume(ws.CostVolumePath(name), ws.CostVolumeDepthsPath(name));
    THROW_IF(volume.cost.Channels() < 2,
             ws.CostVolumePath(name) << ": a cost volume needs at least 2 labels");
    DataTermSamples samples;
    const GroundTruthView gt = ReadGroundTruthView(ground_truth_path, name);
    laps.Lap("read cost volumes and truth");
    const int gt_width = gt.depth.Width(), gt_height = gt.depth.Height();
    const StereoCamera view_camera = ws.ViewCamera(name);
    const StereoCamera truth_camera =
        options.in_true_cameras
            ? TrueCamera(true_cameras, ground_truth_path, name, gt_width, gt_height)
            : view_camera.ScaledToMap(gt_width, gt_height,
                                      GroundTruthViewPath(ground_truth_path, name));
    // The stereo's camera: the view's at the size of the depth maps the same run wrote, where
    // there are any (a max_image_size makes both smaller), else at the image's.
    StereoCamera processing_camera = view_camera;
    for (const char* type : {"photometric", "geometric"}) {
      const std::string map_path = ws.DepthMapPath(name, type);
      if (!ExistsFile(map_path)) continue;
      const MatShape shape = ReadMatShape(map_path);
      processing_camera = view_camera.ScaledToMap(shape.width, shape.height, map_path);
      break;
    }
    const StereoCamera grid_camera = VolumeGridCamera(
        processing_camera, volume.cost.Width(), volume.cost.Height(), ws.CostVolumePath(name));
    // Truth pixels per grid pixel: the truth's picture is the workspace's image at its own
    // size (the true focal length may differ from the workspace's, a mapper's).
    const StereoCamera view_at_truth = view_camera.Scaled(gt_width, gt_height);
    EvaluateView(volume, gt, truth_camera, grid_camera,
                 view_at_truth.K(0, 0) / grid_camera.K(0, 0),
                 view_at_truth.K(1, 1) / grid_camera.K(1, 1), options.min_hair_fraction,
                 &samples);
    result.views.push_back(Summarize(name, samples));
    pooled.Append(samples);
    laps.Lap("cheapest labels against the truth");
  }
  progress.Finish();
  result.overall = Summarize("overall", pooled);

  nlohmann::json json;
  json["workspace_path"] = workspace_path;
  json["ground_truth_path"] = ground_truth_path;
  json["min_hair_fraction"] = options.min_hair_fraction;
  json["in_true_cameras"] = options.in_true_cameras;
  json["overall"] = ToJson(result.overall);
  json["views"] = nlohmann::json::array();
  for (const DataTermMetrics& m : result.views) json["views"].push_back(ToJson(m));
  result.json_path =
      JoinPaths(EvaluationFolder(ws, options.output_path), "data_term_evaluation.json");
  WriteJsonSummary(result.json_path, json);
  laps.Lap("summary");
  return result;
}

}  // namespace hairmvs
