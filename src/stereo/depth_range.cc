#include "src/stereo/depth_range.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "src/core/logging.h"

namespace hairmvs {

bool VisualHullDepthRange(const StereoCamera& ref, const FloatMap& ref_mask,
                          const std::vector<std::pair<StereoCamera, FloatMap>>& others,
                          double search_min_m, double search_max_m, double* min_m,
                          double* max_m, const VisualHullRangeOptions& options) {
  CHECK_EQ(ref_mask.Width(), ref.width);
  CHECK_EQ(ref_mask.Height(), ref.height);
  CHECK_GT(options.pixel_step, 0);
  CHECK_GE(options.num_samples, 2);
  if (!(search_min_m > 0 && search_max_m > search_min_m)) return false;
  for (const auto& [camera, mask] : others) {
    CHECK_EQ(mask.Width(), camera.width);
    CHECK_EQ(mask.Height(), camera.height);
  }

  // Samples uniform in inverse depth: equal steps in disparity.
  std::vector<double> depths(options.num_samples);
  const double inv_near = 1.0 / search_min_m, inv_far = 1.0 / search_max_m;
  for (int k = 0; k < options.num_samples; ++k) {
    depths[k] = 1.0 / (inv_near + (inv_far - inv_near) * k / (options.num_samples - 1));
  }

  // Reference camera coordinates to each other view's homogeneous pixel coordinates:
  // u = K_o (R_o R_r^T (X_r - t_r) + t_o) = A X_r + c.
  struct Projection {
    Eigen::Matrix3d A;
    Eigen::Vector3d c;
    const StereoCamera* camera;
    const FloatMap* mask;
  };
  std::vector<Projection> projections;
  for (const auto& [camera, mask] : others) {
    const Eigen::Matrix3d R_rel = camera.R * ref.R.transpose();
    projections.push_back({camera.K * R_rel, camera.K * (camera.t - R_rel * ref.t), &camera,
                           &mask});
  }

  const int min_observing =
      std::min(options.min_observing_views, static_cast<int>(others.size()));
  const Eigen::Matrix3d K_inv = ref.K.inverse();
  std::vector<double> kept;
  for (int row = options.pixel_step / 2; row < ref.height; row += options.pixel_step) {
    for (int col = options.pixel_step / 2; col < ref.width; col += options.pixel_step) {
      if (!(ref_mask.At(row, col) > 0.5f)) continue;
      // SfM convention: pixel (col, row) is centred at image point (col + 0.5, row + 0.5).
      const Eigen::Vector3d ray = K_inv * Eigen::Vector3d(col + 0.5, row + 0.5, 1.0);
      for (const double depth : depths) {
        const Eigen::Vector3d X = depth * ray;  // z-depth: ray has z = 1
        int observing = 0;
        bool vetoed = false;
        for (const Projection& p : projections) {
          const Eigen::Vector3d u = p.A * X + p.c;
          if (!(u.z() > 0)) continue;  // behind the view: it cannot see the point
          const double x = u.x() / u.z(), y = u.y() / u.z();
          if (!(x >= 0 && y >= 0 && x < p.camera->width && y < p.camera->height)) continue;
          ++observing;
          const int c = std::min(static_cast<int>(x), p.camera->width - 1);
          const int r = std::min(static_cast<int>(y), p.camera->height - 1);
          if (!(p.mask->At(r, c) > 0.5f)) {
            vetoed = true;
            break;
          }
        }
        if (!vetoed && observing >= std::max(1, min_observing)) kept.push_back(depth);
      }
    }
  }
  if (static_cast<int>(kept.size()) < std::max(1, options.min_kept_samples)) return false;
  std::sort(kept.begin(), kept.end());
  const auto at = [&](double percentile) {
    const double p = std::clamp(percentile, 0.0, 100.0) / 100.0;
    const size_t i = std::min(kept.size() - 1, static_cast<size_t>(p * (kept.size() - 1)));
    return kept[i];
  };
  const double lo = at(options.low_percentile), hi = at(options.high_percentile);
  const double margin = std::max(options.margin_fraction * (hi - lo), options.margin_m);
  *min_m = std::max(lo - margin, search_min_m);
  *max_m = std::min(hi + margin, search_max_m);
  return *max_m > *min_m;
}

}  // namespace hairmvs
