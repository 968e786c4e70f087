#include "src/evaluation/evaluation_util.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <utility>

#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace hairmvs {

std::vector<double> Absolute(std::vector<double> values) {
  for (double& v : values) v = std::abs(v);
  return values;
}

double Mean(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  return std::accumulate(values.begin(), values.end(), 0.0) / values.size();
}

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t k = std::min(values.size() - 1,
                            static_cast<size_t>(std::floor(q * (values.size() - 1) + 0.5)));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

DistanceStats SummarizeDistances(std::vector<double> distances_m) {
  DistanceStats stats;
  stats.count = static_cast<long>(distances_m.size());
  if (distances_m.empty()) return stats;
  stats.mean_mm = 1e3 * Mean(distances_m);
  std::sort(distances_m.begin(), distances_m.end());
  const size_t n = distances_m.size();
  stats.median_mm = 1e3 * (n % 2 ? distances_m[n / 2]
                                 : 0.5 * (distances_m[n / 2 - 1] + distances_m[n / 2]));
  stats.p90_mm = 1e3 * distances_m[std::min(n - 1, static_cast<size_t>(0.9 * (n - 1) + 0.5))];
  return stats;
}

DistanceStats SummarizeDistances(std::vector<double> distances_m,
                                 const std::vector<double>& weights) {
  CHECK_EQ(distances_m.size(), weights.size());
  for (const double w : weights) CHECK(w > 0 && std::isfinite(w)) << "weight " << w;
  if (std::adjacent_find(weights.begin(), weights.end(), std::not_equal_to<>()) ==
      weights.end()) {
    return SummarizeDistances(std::move(distances_m));
  }
  std::vector<size_t> order(distances_m.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return distances_m[a] < distances_m[b]; });
  // cumulative[i]: the weight of the i + 1 smallest distances. As copies, the i-th smallest
  // distance holds the copy indices [cumulative[i - 1], cumulative[i]).
  std::vector<double> cumulative(order.size());
  double total = 0, weighted_sum = 0;
  for (size_t i = 0; i < order.size(); ++i) {
    const double w = weights[order[i]];
    total += w;
    weighted_sum += w * distances_m[order[i]];
    cumulative[i] = total;
  }
  auto at_copy = [&](double index) {
    const size_t i = std::upper_bound(cumulative.begin(), cumulative.end(), index) -
                     cumulative.begin();
    return distances_m[order[std::min(i, order.size() - 1)]];
  };
  // SummarizeDistances' rules, over the copies: the median the mean of the middle two of an
  // even count, the 90th percentile the copy at the rounded index.
  const double middle = 0.5 * (total - 1);
  DistanceStats stats;
  stats.count = static_cast<long>(distances_m.size());
  stats.mean_mm = 1e3 * weighted_sum / total;
  stats.median_mm = 1e3 * 0.5 * (at_copy(std::floor(middle)) + at_copy(std::ceil(middle)));
  stats.p90_mm = 1e3 * at_copy(std::floor(0.9 * (total - 1) + 0.5));
  return stats;
}

FloatMap MedianFilterValidDepths(const FloatMap& depth, int k, bool include_invalid) {
  CHECK_EQ(depth.Channels(), 1);
  CHECK(k >= 1 && k % 2 == 1) << "median filter size must be odd";
  const int radius = k / 2;
  const int width = depth.Width();
  const int height = depth.Height();
  FloatMap out(width, height, 1, 0.0f);
#pragma omp parallel for schedule(dynamic, 8)
  for (int r = 0; r < height; ++r) {
    std::vector<float> window;
    window.reserve(static_cast<size_t>(std::min(k, height)) * std::min(k, width));
    for (int c = 0; c < width; ++c) {
      if (!include_invalid && !(depth.At(r, c) > 0)) continue;
      window.clear();
      for (int rr = std::max(0, r - radius); rr <= std::min(height - 1, r + radius); ++rr) {
        for (int cc = std::max(0, c - radius); cc <= std::min(width - 1, c + radius); ++cc) {
          const float d = depth.At(rr, cc);
          if (include_invalid || d > 0) window.push_back(d);
        }
      }
      const size_t n = window.size();
      std::nth_element(window.begin(), window.begin() + n / 2, window.end());
      float median = window[n / 2];
      if (n % 2 == 0) {
        const float lower = *std::max_element(window.begin(), window.begin() + n / 2);
        median = 0.5f * (median + lower);
      }
      out.At(r, c) = median;
    }
  }
  return out;
}

bool CheckImageNames(const std::vector<std::string>& names, std::string* error) {
  for (const std::string& name : names) {
    if (name.empty()) {
      *error = "image_names: empty name";
      return false;
    }
  }
  return true;
}

std::vector<std::string> ViewsToEvaluate(
    const Workspace& ws, const std::vector<std::string>& requested,
    const std::function<std::string(const std::string&)>& path_of, const std::string& none_found) {
  if (!requested.empty()) return ws.SelectImages(requested);
  std::vector<std::string> names, missing;
  for (const std::string& name : ws.ImageNames()) {
    (ExistsFile(path_of(name)) ? names : missing).push_back(name);
  }
  THROW_IF(names.empty(), none_found);
  // The overall figures are over the views evaluated: a view left out must be seen.
  if (!missing.empty()) {
    LOG(WARNING) << missing.size() << " of " << ws.ImageNames().size()
                 << " views are not evaluated, for want of their file (e.g. "
                 << path_of(missing.front()) << "): " << JoinStrings(missing, ", ");
  }
  return names;
}

std::string EvaluationFolder(const Workspace& ws, const std::string& output_path) {
  return output_path.empty() ? JoinPaths(ws.StereoPath(), "evaluation") : output_path;
}

void RequireOutputApartFromInputs(const std::string& output, const std::string& option,
                                  const std::string& ground_truth_path,
                                  const std::string& evaluated_file) {
  if (output.empty()) return;
  THROW_IF(!evaluated_file.empty() && IsSameOrInside(output, evaluated_file),
           option << " " << output << " is the file evaluated, " << evaluated_file
                  << ": give another path for the results");
  THROW_IF(IsSameOrInside(output, ground_truth_path),
           option << " " << output << " lies in the ground truth folder " << ground_truth_path
                  << ": give a path outside it for the results");
}

void WriteJsonSummary(const std::string& path, const nlohmann::json& json) {
  const std::string text = json.dump(1);
  WriteFileAtomically(path, [&text](std::ostream& out) { out << text << "\n"; }, false);
}

GroundTruthCameras ReadTrueCameras(const std::string& gt_path, bool in_true_cameras) {
  if (!in_true_cameras) return GroundTruthCameras();
  RequireGroundTruthDir(gt_path);  // a wrong folder is named as such, not as its missing file
  const std::string path = GroundTruthCamerasPath(gt_path);
  THROW_IF(!ExistsFile(path),
           "Missing " << path << ": the true cameras, in which each depth is compared with the "
                      << "truth (or evaluate with --in_true_cameras 0)");
  return ReadGroundTruthCameras(gt_path);
}

StereoCamera TrueCamera(const GroundTruthCameras& cameras, const std::string& gt_path,
                        const std::string& name, int width, int height) {
  const std::string path = GroundTruthCamerasPath(gt_path);
  const int i = cameras.Find(name);
  THROW_IF(i < 0, path << ": no camera named " << name);
  THROW_IF(cameras.width != width || cameras.height != height,
           path << ": cameras of " << cameras.width << " x " << cameras.height << " px, but "
                << GroundTruthViewPath(gt_path, name) << " is " << width << " x " << height);
  StereoCamera camera;
  camera.K = cameras.K;
  camera.R = cameras.R[i];
  camera.t = cameras.t[i];
  camera.width = width;
  camera.height = height;
  return camera;
}

}  // namespace hairmvs
