#include "src/stereo/depth_range.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "src/core/logging.h"

namespace hairmvs {

namespace {

// The index of percentile `percent` (0-100, clamped) among `size` sorted values: the nearest
// rank below.
size_t PercentileIndex(size_t size, double percent) {
  const double p = std::clamp(percent, 0.0, 100.0) / 100.0;
  return std::min(size - 1, static_cast<size_t>(p * (size - 1)));
}

// That percentile of `values` (not empty), which it reorders.
double Percentile(std::vector<double>* values, double percent) {
  const size_t i = PercentileIndex(values->size(), percent);
  std::nth_element(values->begin(), values->begin() + i, values->end());
  return (*values)[i];
}

// Reference camera coordinates to another view's homogeneous pixel coordinates:
// u = K_o (R_o R_r^T (X_r - t_r) + t_o) = A X_r + c.
struct Projection {
  Eigen::Matrix3d A;
  Eigen::Vector3d c;
  const StereoCamera* camera;
  const FloatMap* mask;
};

enum class HullSample { kInside, kCarved, kUnobserved };

// Where the point X (reference camera frame) lies: inside the hull (seen inside the image by at
// least `min_observing` views, and outside the mask of fewer than `min_carving` of them, all of
// them when fewer see it), carved (outside enough of the masks of the views that see it), or
// unobserved (seen by too few views, whatever their masks say).
HullSample ClassifyHullSample(const std::vector<Projection>& projections, int min_observing,
                              int min_carving, const Eigen::Vector3d& X) {
  int observing = 0, carving = 0;
  for (const Projection& p : projections) {
    const Eigen::Vector3d u = p.A * X + p.c;
    if (!(u.z() > 0)) continue;  // behind the view: it cannot see the point
    const double x = u.x() / u.z(), y = u.y() / u.z();
    if (!(x >= 0 && y >= 0 && x < p.camera->width && y < p.camera->height)) continue;
    ++observing;
    const int c = std::min(static_cast<int>(x), p.camera->width - 1);
    const int r = std::min(static_cast<int>(y), p.camera->height - 1);
    if (!(p.mask->At(r, c) > 0.5f) && ++carving >= min_carving) return HullSample::kCarved;
  }
  if (observing < std::max(1, min_observing)) return HullSample::kUnobserved;
  return carving < std::max(1, std::min(min_carving, observing)) ? HullSample::kInside
                                                                  : HullSample::kCarved;
}

}  // namespace

FloatMap VisualHullIntervals(const StereoCamera& ref, const FloatMap& ref_mask,
                             const std::vector<std::pair<StereoCamera, FloatMap>>& others,
                             double search_min_m, double search_max_m,
                             const VisualHullRangeOptions& options,
                             FloatMap* near_end_causes) {
  const int pixel_step = options.pixel_step;
  const bool find_far_ends = options.find_far_ends;
  CHECK_EQ(ref_mask.Width(), ref.width);
  CHECK_EQ(ref_mask.Height(), ref.height);
  CHECK_GT(pixel_step, 0);
  CHECK_GE(options.num_samples, 2);
  FloatMap intervals(ref.width, ref.height, 2, 0.0f);
  if (near_end_causes != nullptr) *near_end_causes = FloatMap(ref.width, ref.height, 1);
  if (!(search_min_m > 0 && search_max_m > search_min_m)) return intervals;
  std::vector<Projection> projections;
  for (const auto& [camera, mask] : others) {
    CHECK_EQ(mask.Width(), camera.width);
    CHECK_EQ(mask.Height(), camera.height);
    const Eigen::Matrix3d R_rel = camera.R * ref.R.transpose();
    projections.push_back({camera.K * R_rel, camera.K * (camera.t - R_rel * ref.t), &camera,
                           &mask});
  }
  const int min_observing =
      std::min(options.min_observing_views, static_cast<int>(others.size()));
  // Samples uniform in inverse depth (equal steps in disparity), near to far.
  const double inv_near = 1.0 / search_min_m, inv_far = 1.0 / search_max_m;
  const int n = options.num_samples;
  auto inverse_depth = [&](double k) { return inv_near + (inv_far - inv_near) * k / (n - 1); };
  const Eigen::Matrix3d K_inv = ref.K.inverse();
  const int first = pixel_step / 2;
#pragma omp parallel for schedule(dynamic, 4)
  for (int row = first; row < ref.height; row += pixel_step) {
    for (int col = first; col < ref.width; col += pixel_step) {
      if (!(ref_mask.At(row, col) > 0.5f)) continue;
      // SfM convention: pixel (col, row) is centred at image point (col + 0.5, row + 0.5).
      const Eigen::Vector3d ray = K_inv * Eigen::Vector3d(col + 0.5, row + 0.5, 1.0);
      // z-depth: the ray has z = 1.
      auto classify = [&](double k) {
        return ClassifyHullSample(projections, min_observing, options.min_carving_views,
                                  ray / inverse_depth(k));
      };
      auto inside = [&](double k) { return classify(k) == HullSample::kInside; };
      int entry = -1;
      HullSample in_front = HullSample::kUnobserved;  // the sample before the entry
      for (int k = 0; k < n && entry < 0; ++k) {
        const HullSample sample = classify(k);
        if (sample == HullSample::kInside) {
          entry = k;
        } else {
          in_front = sample;
        }
      }
      if (entry < 0) continue;
      if (near_end_causes != nullptr) {
        const NearEndCause cause = entry == 0                          ? NearEndCause::kSearchStart
                                   : in_front == HullSample::kCarved ? NearEndCause::kMasks
                                                                     : NearEndCause::kFrusta;
        near_end_causes->At(row, col) = static_cast<float>(cause);
      }
      int exit = n;  // first sample outside after the entry
      for (int k = entry + 1; find_far_ends && k < n; ++k) {
        if (!inside(k)) {
          exit = k;
          break;
        }
      }
      // Bisection of the transitions (outside, inside] and (inside, outside].
      auto refine = [&](double outside_k, double inside_k) {
        for (int i = 0; i < 8; ++i) {
          const double mid = 0.5 * (outside_k + inside_k);
          (inside(mid) ? inside_k : outside_k) = mid;
        }
        return inside_k;
      };
      const double near_k = entry > 0 ? refine(entry - 1, entry) : entry;
      const double far_k = exit < n ? refine(exit, exit - 1) : n - 1;
      intervals.At(row, col, 0) = static_cast<float>(1.0 / inverse_depth(near_k));
      if (find_far_ends) {
        intervals.At(row, col, 1) = static_cast<float>(1.0 / inverse_depth(far_k));
      }
    }
  }
  return intervals;
}

bool VisualHullDepthRange(const StereoCamera& ref, const FloatMap& ref_mask,
                          const std::vector<std::pair<StereoCamera, FloatMap>>& others,
                          double search_min_m, double search_max_m, double* min_m,
                          double* max_m, const VisualHullRangeOptions& options,
                          HullNearEnd* near_end) {
  VisualHullRangeOptions with_far_ends = options;
  with_far_ends.find_far_ends = true;
  FloatMap causes;
  const FloatMap intervals = VisualHullIntervals(ref, ref_mask, others, search_min_m,
                                                 search_max_m, with_far_ends, &causes);
  std::vector<double> near_ends, far_ends;
  size_t num_at_start = 0, num_cut_by_masks = 0;
  for (size_t i = 0; i < intervals.NumPixels(); ++i) {
    if (intervals.Channel(0)[i] > 0) {
      near_ends.push_back(intervals.Channel(0)[i]);
      far_ends.push_back(intervals.Channel(1)[i]);
      const auto cause = static_cast<NearEndCause>(causes.Channel(0)[i]);
      num_at_start += cause == NearEndCause::kSearchStart;
      num_cut_by_masks += cause == NearEndCause::kMasks;
    }
  }
  if (static_cast<int>(near_ends.size()) < std::max(1, options.min_rays_in_hull)) return false;
  const double lo = Percentile(&near_ends, options.low_percentile);
  const double hi = Percentile(&far_ends, options.high_percentile);
  if (near_end != nullptr) {
    // The low percentile is the search's start when more rays than its index begin there.
    near_end->at_search_start =
        num_at_start > PercentileIndex(near_ends.size(), options.low_percentile);
    const size_t num_inside_search = near_ends.size() - num_at_start;
    near_end->fraction_cut_by_masks =
        num_inside_search > 0 ? static_cast<double>(num_cut_by_masks) / num_inside_search : 0;
  }
  const double margin = std::max(options.margin_fraction * (hi - lo), options.margin_m);
  *min_m = std::max(lo - margin, search_min_m);
  *max_m = std::min(hi + margin, search_max_m);
  return *max_m > *min_m;
}

bool HullAndPointsDepthRange(const StereoCamera& ref, const FloatMap& ref_mask,
                             const std::vector<std::pair<StereoCamera, FloatMap>>& others,
                             const DepthRange& all_points, const DepthRange& in_mask,
                             double* min_m, double* max_m, HullRangeSource* source,
                             const VisualHullRangeOptions& options) {
  double search_min = all_points.min_m, search_max = all_points.max_m;
  if (in_mask.inside_mask) {
    search_min = std::min(search_min, in_mask.min_m);
    search_max = std::max(search_max, in_mask.max_m);
  }
  if (!(search_min > 0 && search_max > search_min)) return false;
  // Each try searches 4 times nearer than the last, the first from half the points' near end.
  // A nearer try counts only where the masks, not the views' frusta, cut most of its rays'
  // near ends: masks that carve nothing near the cameras (drawn loosely) leave a hull that
  // runs up to where the frusta meet, which the points bound better.
  constexpr int kNumTries = 4;
  constexpr double kNearerFactor = 4;
  constexpr double kMinFractionCutByMasks = 0.5;
  double hull_min = 0, hull_max = 0;
  bool found = false, nearer = false;
  for (int attempt = 0; attempt < kNumTries; ++attempt) {
    const double start = 0.5 * search_min / std::pow(kNearerFactor, attempt);
    double try_min = 0, try_max = 0;
    HullNearEnd near_end;
    if (!VisualHullDepthRange(ref, ref_mask, others, start, 2 * search_max, &try_min, &try_max,
                              options, &near_end)) {
      continue;
    }
    const bool cut_by_masks = !near_end.at_search_start &&
                              near_end.fraction_cut_by_masks >= kMinFractionCutByMasks;
    if (attempt == 0 || cut_by_masks) {
      hull_min = try_min;
      hull_max = try_max;
      nearer = attempt > 0;
      found = true;
    }
    // Points in the mask overlapping the first search's hull are on the head (a close-up's
    // cones meet in front of them, so that its hull reaches the start): no nearer search.
    const bool points_overlap_hull = attempt == 0 && in_mask.inside_mask &&
                                     in_mask.max_m >= try_min && in_mask.min_m <= try_max;
    if (!near_end.at_search_start || points_overlap_hull) break;
  }
  if (!found) return false;
  const bool narrowed =
      !nearer && in_mask.inside_mask && in_mask.min_m >= hull_min && in_mask.max_m <= hull_max;
  *source = nearer     ? HullRangeSource::kHullInFrontOfPoints
            : narrowed ? HullRangeSource::kPointsWithinHull
                       : HullRangeSource::kHull;
  *min_m = narrowed ? in_mask.min_m : hull_min;
  *max_m = narrowed ? in_mask.max_m : hull_max;
  return true;
}

bool DepthRangeOfEstimate(const FloatMap& depth, double margin_factor, int min_depths,
                          double* min_m, double* max_m) {
  CHECK_GE(margin_factor, 1.0);
  std::vector<double> depths;
  for (float d : depth.Data()) {
    if (d > 0) depths.push_back(d);
  }
  if (depths.empty() || static_cast<int>(depths.size()) < min_depths) return false;
  *min_m = Percentile(&depths, 1) / margin_factor;
  *max_m = Percentile(&depths, 99) * margin_factor;
  return true;
}

}  // namespace hairmvs
