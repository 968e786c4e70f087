#include "src/stereo/consistency_filter.h"

#include <cmath>

#include "src/core/depth_geometry.h"

namespace hairmvs {

FloatMap FilterDepthMapByConsistency(const FusionView& ref,
                                     const std::vector<const FusionView*>& others,
                                     double max_reprojection_error_px, int min_consistent_views,
                                     ConsistencyFilterStats* stats) {
  FloatMap filtered = ref.depth;
  const Eigen::Matrix3d R_t = ref.R.transpose();
  const int width = ref.depth.Width(), height = ref.depth.Height();
  int num_checked = 0, num_kept = 0;
#pragma omp parallel for schedule(dynamic, 8) reduction(+ : num_checked, num_kept)
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const float depth = ref.depth.At(row, col);
      if (!(depth > 0)) continue;
      ++num_checked;
      const Eigen::Vector3d world = R_t * (BackProjectPixel(ref.K, col, row, depth) - ref.t);
      const Eigen::Vector2d centre(col + 0.5, row + 0.5);
      int consistent = 0;
      for (const FusionView* other : others) {
        int c, r;
        double z;
        if (!other->Project(world, &c, &r, &z)) continue;
        const float other_depth = other->depth.At(r, c);
        if (!(other_depth > 0)) continue;
        // Forward-backward: the other view's surface point at that pixel, seen from the
        // reference (COLMAP's geometric consistency error). The exact (sub-pixel) projection
        // is used, so that an exact surface reprojects exactly.
        const Eigen::Vector3d other_world = other->SurfaceOnRay(world, z, other_depth);
        const Eigen::Vector3d back = ref.K * (ref.R * other_world + ref.t);
        if (!(back.z() > 0)) continue;
        const Eigen::Vector2d reprojected = back.head<2>() / back.z();
        if ((reprojected - centre).norm() <= max_reprojection_error_px) ++consistent;
      }
      if (consistent >= min_consistent_views) {
        ++num_kept;
      } else {
        filtered.At(row, col) = 0.0f;
      }
    }
  }
  if (stats != nullptr) {
    stats->num_checked = num_checked;
    stats->num_kept = num_kept;
  }
  return filtered;
}

}  // namespace hairmvs
