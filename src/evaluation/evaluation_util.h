#pragma once
// Small helpers shared by the evaluators: distance statistics, the median filter, which views
// to read and where the summaries go.

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

#include "colmap_ext/workspace.h"
#include "hairmvs/evaluation.h"
#include "src/core/depth_geometry.h"
#include "src/core/float_map.h"
#include "src/evaluation/ground_truth.h"

namespace hairmvs {

// |v| of each value (signed errors to absolute ones).
std::vector<double> Absolute(std::vector<double> values);

// Mean, median and 90th percentile of distances given in metres, reported in mm.
DistanceStats SummarizeDistances(std::vector<double> distances_m);
// The same where each distance stands for `weights[i]` (> 0) copies of itself (a sample of
// each view's pixels, pooled over views of different sizes): the figures of the copies, by
// SummarizeDistances' rules (exactly so for whole weights; a fractional weight is a fraction
// of a copy). Equal weights give SummarizeDistances' figures exactly.
DistanceStats SummarizeDistances(std::vector<double> distances_m,
                                 const std::vector<double>& weights);
// Percentile q in [0, 1] (nearest rank on the sorted values); NaN for an empty vector.
double Percentile(std::vector<double> values, double q);
double Mean(const std::vector<double>& values);

// k x k median of the valid (> 0) depths around each valid pixel (the median of an even
// count is the mean of the two middle values); invalid pixels stay 0. k odd.
// include_invalid: a plain median over every pixel of the window (zeros included, the
// window clamped at the image border), computed for every pixel, like
// scipy.ndimage.median_filter(depth, k) up to its border rule.
FloatMap MedianFilterValidDepths(const FloatMap& depth, int k, bool include_invalid = false);

// The views a workspace evaluator reads: `requested` when given (each must be an image of the
// workspace), else every image of the workspace whose `path_of(name)` exists, with a warning
// naming those left out. Throws hairmvs::Error with `none_found` when none does.
std::vector<std::string> ViewsToEvaluate(
    const Workspace& ws, const std::vector<std::string>& requested,
    const std::function<std::string(const std::string&)>& path_of, const std::string& none_found);
// An evaluator's output folder: `output_path`, or <workspace>/stereo/evaluation when empty.
std::string EvaluationFolder(const Workspace& ws, const std::string& output_path);
// Throws hairmvs::Error naming `option` unless `output` (a file or folder an evaluation
// writes; empty = none) lies outside the ground truth folder and is not the file evaluated
// (`evaluated_file`, empty = none): an evaluation never writes over its inputs.
void RequireOutputApartFromInputs(const std::string& output, const std::string& option,
                                  const std::string& ground_truth_path,
                                  const std::string& evaluated_file = "");
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

// gt_path/cameras.npz when `in_true_cameras` (empty cameras otherwise). Throws hairmvs::Error
// naming the file, and the way to compare at the same pixels instead, when it is missing.
GroundTruthCameras ReadTrueCameras(const std::string& gt_path, bool in_true_cameras);
// The camera `name` was rendered with (gt_path/cameras.npz, read into `cameras`), on the true
// maps' grid of width x height: how the evaluators carry a depth between the workspace's
// camera (ViewCamera), in which the maps are estimated, and the true camera
// (DepthEvaluationOptions::in_true_cameras), and how evaluate_mesh back-projects the true
// maps. Throws hairmvs::Error naming the file when the camera is absent or of another size.
StereoCamera TrueCamera(const GroundTruthCameras& cameras, const std::string& gt_path,
                        const std::string& name, int width, int height);

// "Section.field" checks shared by the option structs.
bool CheckImageNames(const std::vector<std::string>& names, std::string* error);

}  // namespace hairmvs
