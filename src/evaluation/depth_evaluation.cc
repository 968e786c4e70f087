// hairmvs evaluate_depth: depth maps of a workspace against the true depth and strands.

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <optional>
#include <random>
#include <utility>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/evaluation.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/progress.h"
#include "src/evaluation/depth_evaluation.h"
#include "src/evaluation/evaluation_util.h"
#include "src/evaluation/ground_truth.h"

namespace hairmvs {
namespace {

// The per-pixel samples of one view (or of all views pooled).
struct DepthSamples {
  long num_hair_pixels = 0;
  long num_background_depths = 0;  // depths where the truth is background
  // depth - true depth of the hair pixels with a depth, near the silhouette or not.
  std::vector<double> silhouette_errors_m, interior_errors_m;
  std::vector<double> distances_3d_m;  // a subset of them, back-projected
  // How many pixels with a depth each of distances_3d_m stands for (its view's count over its
  // sample's, DepthEvaluationOptions::max_points_3d_per_view), so that pooled views weigh
  // by their pixels as in the other columns.
  std::vector<double> distance_weights;
  std::vector<double> layers;          // of the pixels whose true depth window is all hair
  // The signed errors' smooth part and the rest (DepthEvaluationOptions::smooth_error_window_px).
  std::vector<double> smooth_errors_m, rough_errors_m;

  void Append(const DepthSamples& other) {
    num_hair_pixels += other.num_hair_pixels;
    num_background_depths += other.num_background_depths;
    layers.insert(layers.end(), other.layers.begin(), other.layers.end());
    for (auto [to, from] : {std::pair(&silhouette_errors_m, &other.silhouette_errors_m),
                            std::pair(&interior_errors_m, &other.interior_errors_m),
                            std::pair(&distances_3d_m, &other.distances_3d_m),
                            std::pair(&distance_weights, &other.distance_weights),
                            std::pair(&smooth_errors_m, &other.smooth_errors_m),
                            std::pair(&rough_errors_m, &other.rough_errors_m)}) {
      to->insert(to->end(), from->begin(), from->end());
    }
  }
};

// Median in mm of values in metres (signed or not; the median of an even count is the mean of
// the middle two, as for the distances).
double MedianMm(const std::vector<double>& values_m) {
  return SummarizeDistances(values_m).median_mm;
}

// Where the ray of `true_camera`'s pixel (col, row) meets the depth map `depth` of `camera`
// (the workspace's, whose pose may differ from the true one, and whose map may be smaller than
// the truth): from `start_depth` on, each step takes the map's depth where the ray's point
// projects (SampleDepthMap: between the map's pixel centres, which a smaller map puts on the
// truth's pixel edges) and moves along the ray to the point at that depth in the map's camera,
// at most four steps: where the two cameras are the same the first step is exact; a fraction of
// a degree apart, each step shrinks the gap by the map's slope along the ray, and the fourth is
// taken as it is (at a depth edge the steps may alternate between two pixels). `*world` is the
// point met, `*true_depth` its z in the true camera. False where the ray meets no depth or
// leaves the map.
bool DepthAlongTrueRay(const StereoCamera& true_camera, int col, int row, double start_depth,
                       const StereoCamera& camera, const FloatMap& depth, Eigen::Vector3d* world,
                       double* true_depth) {
  // The ray's point of z-depth z in the true camera is origin + z direction; its z-depth in
  // the map's camera grows by `slope` per unit of z.
  const Eigen::Vector3d origin = true_camera.Center();
  const Eigen::Vector3d direction = true_camera.BackProject(col, row, 1.0) - origin;
  const double slope = (camera.R * direction).z();
  if (!(slope > 0)) return false;
  double z = start_depth;
  for (int step = 0; step < 4; ++step) {
    double point_depth = 0, map_depth = 0;
    if (!MapDepthOnRay(camera.K, camera.R, camera.t, depth, origin + z * direction, &point_depth,
                       &map_depth)) {
      return false;
    }
    const double next = z + (map_depth - point_depth) / slope;
    if (!(next > 0)) return false;
    const bool settled = std::abs(next - z) <= 1e-9 * z;
    z = next;
    if (settled) break;
  }
  *world = origin + z * direction;
  *true_depth = z;
  return true;
}

// The fraction of the true hair depths of the k x k window around gt pixel (r, c) that lie in
// front of `depth` (ties count half); -1 when the window leaves the image or holds a pixel
// that is not hair.
double LayerInWindow(const GroundTruthView& gt, int r, int c, int k, double depth) {
  const int width = gt.depth.Width(), height = gt.depth.Height(), half = k / 2;
  if (r < half || c < half || r + half >= height || c + half >= width) return -1;
  double in_front = 0;
  for (int wr = r - half; wr <= r + half; ++wr) {
    for (int wc = c - half; wc <= c + half; ++wc) {
      if (gt.label[static_cast<size_t>(wr) * width + wc] != kLabelHair) return -1;
      const double truth = gt.depth.At(wr, wc);
      in_front += truth < depth ? 1.0 : truth == depth ? 0.5 : 0.0;
    }
  }
  return in_front / (k * k);
}

// For each pixel of `has_depth` (255), the mean of `signed_errors` over the pixels of
// `has_depth` in its k x k window (the smooth part) and its own error less that mean.
void SplitErrorByScale(const cv::Mat& signed_errors, const cv::Mat& has_depth, int k,
                       std::vector<double>* smooth_errors, std::vector<double>* rough_errors) {
  cv::Mat weights, error_sums, weight_sums;
  has_depth.convertTo(weights, CV_64FC1, 1.0 / 255);
  const cv::Size window(k, k);
  const cv::Point centre(-1, -1);
  cv::boxFilter(signed_errors, error_sums, -1, window, centre, false, cv::BORDER_CONSTANT);
  cv::boxFilter(weights, weight_sums, -1, window, centre, false, cv::BORDER_CONSTANT);
  for (int r = 0; r < signed_errors.rows; ++r) {
    for (int c = 0; c < signed_errors.cols; ++c) {
      if (!has_depth.at<uint8_t>(r, c)) continue;
      const double smooth = error_sums.at<double>(r, c) / weight_sums.at<double>(r, c);
      smooth_errors->push_back(smooth);
      rough_errors->push_back(signed_errors.at<double>(r, c) - smooth);
    }
  }
}

DepthMetrics Summarize(const std::string& name, const DepthSamples& samples) {
  DepthMetrics m;
  m.name = name;
  m.num_hair_pixels = samples.num_hair_pixels;
  std::vector<double> signed_errors_m = samples.silhouette_errors_m;
  signed_errors_m.insert(signed_errors_m.end(), samples.interior_errors_m.begin(),
                         samples.interior_errors_m.end());
  const std::vector<double> abs_errors_m = Absolute(signed_errors_m);
  m.num_with_depth = static_cast<long>(abs_errors_m.size());
  m.completeness = m.num_hair_pixels > 0 ? static_cast<double>(m.num_with_depth) / m.num_hair_pixels
                                         : 0.0;
  m.num_background_depths = samples.num_background_depths;
  const long num_depths = m.num_with_depth + m.num_background_depths;
  m.background_depth_fraction =
      num_depths > 0 ? static_cast<double>(m.num_background_depths) / num_depths : 0.0;
  const DistanceStats errors = SummarizeDistances(abs_errors_m);
  m.mean_abs_error_mm = errors.mean_mm;
  m.median_abs_error_mm = errors.median_mm;
  long n1 = 0, n2 = 0, n5 = 0;
  for (double e : abs_errors_m) {
    n1 += e <= 1e-3;
    n2 += e <= 2e-3;
    n5 += e <= 5e-3;
  }
  const double n = std::max<long>(1, m.num_with_depth);
  m.within_1mm = n1 / n;
  m.within_2mm = n2 / n;
  m.within_5mm = n5 / n;
  m.median_signed_error_mm = MedianMm(signed_errors_m);
  m.silhouette_fraction = samples.silhouette_errors_m.size() / n;
  m.silhouette_median_abs_error_mm = MedianMm(Absolute(samples.silhouette_errors_m));
  m.silhouette_median_signed_error_mm = MedianMm(samples.silhouette_errors_m);
  m.interior_median_abs_error_mm = MedianMm(Absolute(samples.interior_errors_m));
  m.interior_median_signed_error_mm = MedianMm(samples.interior_errors_m);
  m.num_layer_pixels = static_cast<long>(samples.layers.size());
  m.median_layer = Percentile(samples.layers, 0.5);
  m.smooth_median_abs_error_mm = MedianMm(Absolute(samples.smooth_errors_m));
  m.rough_median_abs_error_mm = MedianMm(Absolute(samples.rough_errors_m));
  const DistanceStats accuracy =
      SummarizeDistances(samples.distances_3d_m, samples.distance_weights);
  m.num_points_3d = accuracy.count;
  m.accuracy_3d_mean_mm = accuracy.mean_mm;
  m.accuracy_3d_median_mm = accuracy.median_mm;
  m.accuracy_3d_p90_mm = accuracy.p90_mm;
  return m;
}

nlohmann::json ToJson(const DepthMetrics& m) {
  return {{"name", m.name},
          {"num_hair_pixels", m.num_hair_pixels},
          {"num_with_depth", m.num_with_depth},
          {"completeness", m.completeness},
          {"num_background_depths", m.num_background_depths},
          {"background_depth_fraction", m.background_depth_fraction},
          {"mean_abs_error_mm", m.mean_abs_error_mm},
          {"median_abs_error_mm", m.median_abs_error_mm},
          {"within_1mm", m.within_1mm},
          {"within_2mm", m.within_2mm},
          {"within_5mm", m.within_5mm},
          {"median_signed_error_mm", m.median_signed_error_mm},
          {"silhouette_fraction", m.silhouette_fraction},
          {"silhouette_median_abs_error_mm", m.silhouette_median_abs_error_mm},
          {"silhouette_median_signed_error_mm", m.silhouette_median_signed_error_mm},
          {"interior_median_abs_error_mm", m.interior_median_abs_error_mm},
          {"interior_median_signed_error_mm", m.interior_median_signed_error_mm},
          {"num_layer_pixels", m.num_layer_pixels},
          {"median_layer", m.median_layer},
          {"smooth_median_abs_error_mm", m.smooth_median_abs_error_mm},
          {"rough_median_abs_error_mm", m.rough_median_abs_error_mm},
          {"num_points_3d", m.num_points_3d},
          {"accuracy_3d_mean_mm", m.accuracy_3d_mean_mm},
          {"accuracy_3d_median_mm", m.accuracy_3d_median_mm},
          {"accuracy_3d_p90_mm", m.accuracy_3d_p90_mm}};
}

std::string TableRow(const DepthMetrics& m) {
  char line[256];
  std::snprintf(line, sizeof(line),
                "%-14s %9ld %7.1f%% %5.1f%% %8.2f %8.2f %6.1f%% %6.1f%% %6.1f%% %8.3f %8.3f"
                " %7.2f %6.1f%% %7.2f %7.2f %7.2f %7.2f %5.0f%% %7.2f %7.2f\n",
                m.name.c_str(), m.num_hair_pixels, 100 * m.completeness,
                100 * m.background_depth_fraction, m.mean_abs_error_mm,
                m.median_abs_error_mm, 100 * m.within_1mm, 100 * m.within_2mm,
                100 * m.within_5mm, m.accuracy_3d_mean_mm, m.accuracy_3d_median_mm,
                m.median_signed_error_mm, 100 * m.silhouette_fraction,
                m.silhouette_median_abs_error_mm, m.silhouette_median_signed_error_mm,
                m.interior_median_abs_error_mm, m.interior_median_signed_error_mm,
                100 * m.median_layer, m.smooth_median_abs_error_mm, m.rough_median_abs_error_mm);
  return line;
}

}  // namespace

bool DepthEvaluationOptions::Check(std::string* error) const {
  if (depth_type != "geometric" && depth_type != "photometric") {
    *error = "--depth_type must be geometric or photometric";
    return false;
  }
  if (!(error_image_max_mm > 0)) {
    *error = "--error_image_max_mm must be > 0";
    return false;
  }
  if (max_points_3d_per_view < 0) {
    *error = "--max_points_3d_per_view must be >= 0";
    return false;
  }
  if (silhouette_band_px < 0) {
    *error = "--silhouette_band_px must be >= 0";
    return false;
  }
  // Windows wider than any image are refused before the maps are read (one of 10^8 px ran
  // out of memory).
  if (layer_window_px < 0 || layer_window_px > 999 ||
      (layer_window_px > 0 && layer_window_px % 2 == 0)) {
    *error = "--layer_window_px must be 0 or odd, at most 999";
    return false;
  }
  if (smooth_error_window_px < 0 || smooth_error_window_px > 999 ||
      (smooth_error_window_px > 0 && smooth_error_window_px % 2 == 0)) {
    *error = "--smooth_error_window_px must be 0 or odd, at most 999";
    return false;
  }
  if (!(strand_spacing_m > 0)) {
    *error = "--strand_spacing_m must be > 0";
    return false;
  }
  return CheckImageNames(image_names, error);
}

std::string DepthEvaluationResult::Table() const {
  // bg = depths where the truth is background, of the depths on hair or background (they count
  // in the 3D columns, not in the per-pixel ones); sil = hair pixels within
  // silhouette_band_px of the background, int = the others;
  // signed medians (sgn) > 0: behind the truth; layer: median fraction of the true depths
  // around a pixel in front of its depth (50% = their median); smooth / rough: the medians of
  // the error's part that is smooth over smooth_error_window_px and of the rest.
  return EvaluationTable(
      "view           hair_px  complete    bg  mean_mm  med_mm  <=1mm  <=2mm  <=5mm  3d_mean  "
      "3d_med  sgn_mm    sil% sil_med sil_sgn int_med int_sgn  layer  smooth   rough\n",
      views, overall, json_path, TableRow);
}

namespace {

// The views whose depth maps of options.depth_type are evaluated; an error when there are none.
std::vector<std::string> DepthMapsToEvaluate(const Workspace& ws,
                                             const DepthEvaluationOptions& options) {
  return ViewsToEvaluate(
      ws, options.image_names,
      [&](const std::string& name) { return ws.DepthMapPath(name, options.depth_type); },
      "No " + options.depth_type + " depth maps in " + JoinPaths(ws.StereoPath(), "depth_maps"));
}

}  // namespace

namespace {

// The evaluation of `names` (DepthMapsToEvaluate's) of the workspace `ws`, read once by each
// public overload.
DepthEvaluationResult EvaluateWorkspaceDepthMaps(const Workspace& ws,
                                                 const std::vector<std::string>& names,
                                                 const std::string& ground_truth_path,
                                                 const DepthEvaluationOptions& options,
                                                 const StrandDistance& strand_distance,
                                                 StageTimings* timings) {
  StageLaps laps(timings);
  const std::string output_path = EvaluationFolder(ws, options.output_path);
  RequireOutputApartFromInputs(output_path, "--output_path", ground_truth_path);

  const GroundTruthCameras true_cameras =
      ReadTrueCameras(ground_truth_path, options.in_true_cameras);

  DepthEvaluationResult result;
  DepthSamples pooled;
  std::mt19937 rng(options.seed);
  // The error pictures are made in a hidden folder and moved into place with the summary, once
  // every view is evaluated: a run that stops on a bad file leaves the pictures and the summary
  // of the run before, which agree.
  std::optional<StagingDir> pictures;
  std::vector<std::string> picture_names;
  if (options.write_error_images) pictures.emplace(output_path, "evaluate_depth");
  Progress progress("evaluate_depth", static_cast<int>(names.size()));
  for (size_t v = 0; v < names.size(); ++v) {
    const std::string& name = names[v];
    progress.Start(static_cast<int>(v), name);
    const FloatMap depth = ReadMat(ws.DepthMapPath(name, options.depth_type));
    THROW_IF(depth.Channels() != 1,
             ws.DepthMapPath(name, options.depth_type) << ": a depth map has 1 channel");
    const GroundTruthView gt = ReadGroundTruthView(ground_truth_path, name);
    laps.Lap("read maps and truth");
    const int width = depth.Width(), height = depth.Height();
    const int gt_width = gt.depth.Width(), gt_height = gt.depth.Height();
    const StereoCamera camera =
        ws.ViewCamera(name).ScaledToMap(width, height, ws.DepthMapPath(name, options.depth_type));
    // In the true camera: each true hair pixel sampled is compared where the ray through its
    // centre meets the map (DepthAlongTrueRay), so that every one counts once, with a depth or
    // without. (Through the truth's pixel, not the map's: a map of half the size has its pixel
    // centres on the truth's pixel edges.)
    std::optional<StereoCamera> true_camera;
    if (options.in_true_cameras) {
      true_camera = TrueCamera(true_cameras, ground_truth_path, name, gt_width, gt_height);
    }

    // Distance (gt pixels) of each gt pixel to the nearest background pixel; the band in
    // depth-map pixels scaled to gt pixels.
    cv::Mat foreground(gt_height, gt_width, CV_8UC1);
    for (int r = 0; r < gt_height; ++r) {
      for (int c = 0; c < gt_width; ++c) {
        foreground.at<uint8_t>(r, c) =
            gt.label[static_cast<size_t>(r) * gt_width + c] == kLabelBackground ? 0 : 255;
      }
    }
    cv::Mat distance_to_background;
    cv::distanceTransform(foreground, distance_to_background, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    const double silhouette_band_gt_px =
        options.silhouette_band_px * static_cast<double>(gt_width) / width;

    DepthSamples samples;
    std::vector<Eigen::Vector3d> points;
    // Error pictures: black background, dark grey skin, grey = hair pixel without a depth;
    // a hair pixel with a depth: its |error| (blue 0 mm .. red error_image_max_mm), and in the
    // signed picture its signed error (blue in front, white 0, red behind, saturated at
    // error_image_max_mm).
    cv::Mat error_image(height, width, CV_8UC3, cv::Scalar(0, 0, 0));
    cv::Mat has_depth(height, width, CV_8UC1, cv::Scalar(0));
    cv::Mat signed_errors(height, width, CV_64FC1, cv::Scalar(0));
    for (int r = 0; r < height; ++r) {
      const int same_row = std::min(gt_height - 1, (2 * r + 1) * gt_height / (2 * height));
      for (int c = 0; c < width; ++c) {
        const int gr = same_row;
        const int gc = std::min(gt_width - 1, (2 * c + 1) * gt_width / (2 * width));
        // The depth compared: the map's own at this pixel, or in the true camera the z of the
        // map's point that this pixel's ray meets, followed from the map's depth here or else
        // from the true one.
        double compared_depth = depth.At(r, c);
        Eigen::Vector3d world = Eigen::Vector3d::Zero();
        bool has_estimate = compared_depth > 0;
        if (true_camera) {
          const double start = has_estimate ? compared_depth : gt.depth.At(gr, gc);
          has_estimate = start > 0 && DepthAlongTrueRay(*true_camera, gc, gr, start, camera,
                                                        depth, &world, &compared_depth);
        } else if (has_estimate) {
          world = camera.BackProject(c, r, compared_depth);
        }
        const uint8_t label = gt.label[static_cast<size_t>(gr) * gt_width + gc];
        cv::Vec3b& pixel = error_image.at<cv::Vec3b>(r, c);
        if (label != kLabelHair) {
          if (label == kLabelSkin) pixel = cv::Vec3b(40, 40, 40);
          if (has_estimate) pixel = cv::Vec3b(90, 60, 60);  // a depth outside the hair
          // A depth beyond the hair's silhouette is an error of the map: in the 3D accuracy
          // (every depth pixel, issue 4), though no true depth there gives a per-pixel one. One
          // on the skin is the skin's, not a strand's: in neither.
          if (has_estimate && label == kLabelBackground) {
            ++samples.num_background_depths;
            points.push_back(world);
          }
          continue;
        }
        ++samples.num_hair_pixels;
        if (!has_estimate) {
          pixel = cv::Vec3b(160, 160, 160);  // missing: grey
          continue;
        }
        const double signed_error = compared_depth - gt.depth.At(gr, gc);
        const bool near_silhouette =
            distance_to_background.at<float>(gr, gc) <= silhouette_band_gt_px;
        (near_silhouette ? samples.silhouette_errors_m : samples.interior_errors_m)
            .push_back(signed_error);
        if (options.layer_window_px > 0) {
          const double layer =
              LayerInWindow(gt, gr, gc, options.layer_window_px, compared_depth);
          if (layer >= 0) samples.layers.push_back(layer);
        }
        has_depth.at<uint8_t>(r, c) = 255;
        signed_errors.at<double>(r, c) = signed_error;
        points.push_back(world);
      }
    }
    double weight_3d = 1;
    if (options.max_points_3d_per_view > 0 &&
        points.size() > static_cast<size_t>(options.max_points_3d_per_view)) {
      weight_3d = static_cast<double>(points.size()) / options.max_points_3d_per_view;
      std::shuffle(points.begin(), points.end(), rng);
      points.resize(options.max_points_3d_per_view);
    }
    if (options.smooth_error_window_px > 0) {
      SplitErrorByScale(signed_errors, has_depth, options.smooth_error_window_px,
                        &samples.smooth_errors_m, &samples.rough_errors_m);
    }
    laps.Lap("per-pixel errors");
    progress.Stage("3D distances");
    samples.distances_3d_m = strand_distance.Distances(points);
    samples.distance_weights.assign(samples.distances_3d_m.size(), weight_3d);
    result.views.push_back(Summarize(name, samples));
    laps.Lap("3D distances");

    if (options.write_error_images) {
      // The errors on the colour scale: |error| in 0..255 for the colour map, the signed one in
      // [-1, 1].
      cv::Mat levels(height, width, CV_8UC1, cv::Scalar(0));
      cv::Mat signed_image = error_image.clone();
      for (int r = 0; r < height; ++r) {
        for (int c = 0; c < width; ++c) {
          if (!has_depth.at<uint8_t>(r, c)) continue;
          const double signed_error = signed_errors.at<double>(r, c);
          const double abs_level =
              std::min(1.0, 1e3 * std::abs(signed_error) / options.error_image_max_mm);
          levels.at<uint8_t>(r, c) = static_cast<uint8_t>(std::lround(255 * abs_level));
          const auto level = static_cast<float>(
              std::clamp(1e3 * signed_error / options.error_image_max_mm, -1.0, 1.0));
          const auto fade = static_cast<uint8_t>(std::lround(255 * (1 - std::abs(level))));
          signed_image.at<cv::Vec3b>(r, c) =  // BGR
              level > 0 ? cv::Vec3b(fade, fade, 255) : cv::Vec3b(255, fade, fade);
        }
      }
      cv::Mat colours;
      cv::applyColorMap(levels, colours, cv::COLORMAP_JET);
      colours.copyTo(error_image, has_depth);
      for (const auto& [suffix, image] : {std::pair(".error.png", &error_image),
                                          std::pair(".signed_error.png", &signed_image)}) {
        picture_names.push_back(name + suffix);
        WriteImage(JoinPaths(pictures->Path(), picture_names.back()), *image);
      }
      laps.Lap("error pictures");
    }
    pooled.Append(samples);
  }
  progress.Finish();
  result.overall = Summarize("overall", pooled);

  nlohmann::json json;
  json["workspace_path"] = ws.Path();
  json["ground_truth_path"] = ground_truth_path;
  json["depth_type"] = options.depth_type;
  json["pixel_convention"] = "SfM: pixel (col, row) centred at (col + 0.5, row + 0.5)";
  json["in_true_cameras"] = options.in_true_cameras;
  json["max_points_3d_per_view"] = options.max_points_3d_per_view;
  json["strand_spacing_m"] = options.strand_spacing_m;
  json["overall"] = ToJson(result.overall);
  json["views"] = nlohmann::json::array();
  for (const DepthMetrics& m : result.views) json["views"].push_back(ToJson(m));
  result.json_path = JoinPaths(output_path, "depth_evaluation.json");
  if (pictures) pictures->Commit(picture_names, /*replace=*/true);
  WriteJsonSummary(result.json_path, json);
  laps.Lap("summary");
  return result;
}

}  // namespace

DepthEvaluationResult EvaluateDepthMaps(const std::string& workspace_path,
                                        const std::string& ground_truth_path,
                                        const DepthEvaluationOptions& options,
                                        StageTimings* timings) {
  std::string error;
  THROW_IF(!options.Check(&error), error);
  StageLaps laps(timings);
  // The maps looked for before the strands are indexed (seconds): a workspace without them
  // is named at once.
  const Workspace ws = Workspace::Read(workspace_path);
  const std::vector<std::string> names = DepthMapsToEvaluate(ws, options);
  LOG(INFO) << "Indexing the true strands of " << ground_truth_path;
  const GroundTruthStrands strands = ReadGroundTruthStrands(ground_truth_path);
  Timer timer;
  const StrandDistance strand_distance(strands, options.strand_spacing_m);
  LOG(INFO) << "True strands: " << strands.NumStrands() << " strands, "
            << strand_distance.NumSamples() << " centreline samples (" << std::fixed
            << std::setprecision(1) << timer.ElapsedSeconds() << " s)";
  laps.Lap("true strands");
  return EvaluateWorkspaceDepthMaps(ws, names, ground_truth_path, options, strand_distance,
                                    timings);
}

DepthEvaluationResult EvaluateDepthMaps(const std::string& workspace_path,
                                        const std::string& ground_truth_path,
                                        const DepthEvaluationOptions& options,
                                        const StrandDistance& strand_distance,
                                        StageTimings* timings) {
  std::string error;
  THROW_IF(!options.Check(&error), error);
  const Workspace ws = Workspace::Read(workspace_path);
  return EvaluateWorkspaceDepthMaps(ws, DepthMapsToEvaluate(ws, options), ground_truth_path,
                                    options, strand_distance, timings);
}

}  // namespace hairmvs
