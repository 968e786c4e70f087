#pragma once
// Small helpers shared by the evaluators: distance statistics, the median filter, which views
// to read and where the summaries go.

#include <nlohmann/json.hpp>

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "colmap_ext/workspace.h"
#include "hairmvs/evaluation.h"
#include "src/core/float_map.h"
#include "src/evaluation/ground_truth.h"

namespace hairmvs {

// Mean, median and 90th percentile of distances given in metres, reported in mm.
DistanceStats SummarizeDistances(std::vector<double> distances_m);
// Percentile q in [0, 1] (nearest rank on the sorted values); 0 for an empty vector.
double Percentile(std::vector<double> values, double q);
double Mean(const std::vector<double>& values);

// k x k median of the valid (> 0) depths around each valid pixel (the median of an even
// count is the mean of the two middle values); invalid pixels stay 0. k odd.
// include_invalid: a plain median over every pixel of the window (zeros included, the
// window clamped at the image border), computed for every pixel, like
// scipy.ndimage.median_filter(depth, k) up to its border rule.
FloatMap MedianFilterValidDepths(const FloatMap& depth, int k, bool include_invalid = false);

// The views a workspace evaluator reads: `requested` when given, else every image of the
// workspace whose `path_of(name)` exists. Throws hairmvs::Error with `none_found` when none does.
std::vector<std::string> ViewsToEvaluate(
    const Workspace& ws, const std::vector<std::string>& requested,
    const std::function<std::string(const std::string&)>& path_of, const std::string& none_found);
// An evaluator's output folder: `output_path`, or <workspace>/stereo/evaluation when empty.
std::string EvaluationFolder(const Workspace& ws, const std::string& output_path);
// Writes an evaluator's JSON summary atomically (indented, newline-terminated).
void WriteJsonSummary(const std::string& path, const nlohmann::json& json);

// An evaluator's printed table: `header`, `row(m)` per view and for the overall metrics, and
// where the JSON summary went.
template <typename Metrics, typename RowFn>
std::string EvaluationTable(const std::string& header, const std::vector<Metrics>& views,
                            const Metrics& overall, const std::string& json_path, RowFn row) {
  std::string table = header;
  for (const Metrics& m : views) table += row(m);
  table += row(overall);
  if (!json_path.empty()) table += "Summary: " + json_path + "\n";
  return table;
}

// A view's camera on a width x height pixel grid (SfM convention: pixel (col, row) is centred
// at (col + 0.5, row + 0.5)) and its pose, X_cam = R X_world + t: how the evaluators carry a
// depth between the workspace's camera, in which the maps are estimated, and the true camera,
// in which the truth was rendered (DepthEvaluationOptions::in_true_cameras).
struct GridCamera {
  Eigen::Matrix3d K;
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  int width = 0;
  int height = 0;

  // The world point seen at pixel (col, row) with z-depth `depth`.
  Eigen::Vector3d BackProject(int col, int row, double depth) const;
  // The pixel a world point lands in and its z-depth; false when it is behind the camera or
  // off the grid.
  bool Project(const Eigen::Vector3d& world, int* col, int* row, double* depth) const;
};
// The workspace's camera of image `name`, scaled to a width x height grid.
GridCamera WorkspaceGridCamera(const Workspace& ws, const std::string& name, int width,
                               int height);
// gt_path/cameras.npz when `in_true_cameras` (empty cameras otherwise). Throws hairmvs::Error
// naming the file, and the way to compare at the same pixels instead, when it is missing.
GroundTruthCameras ReadTrueCameras(const std::string& gt_path, bool in_true_cameras);
// The camera `name` was rendered with (gt_path/cameras.npz, read into `cameras`), on the true
// maps' grid of width x height. Throws hairmvs::Error naming the file when the camera is
// absent or of another size.
GridCamera TrueGridCamera(const GroundTruthCameras& cameras, const std::string& gt_path,
                          const std::string& name, int width, int height);

// "Section.field" checks shared by the option structs.
bool CheckImageNames(const std::vector<std::string>& names, std::string* error);

}  // namespace hairmvs
