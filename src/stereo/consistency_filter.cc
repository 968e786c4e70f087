#include "src/stereo/consistency_filter.h"

#include <cmath>
#include <vector>

#include "src/core/depth_geometry.h"

namespace hairmvs {

bool ForwardBackwardErrorPx(const FusionView& other, const Eigen::Vector3d& world,
                            const Eigen::Matrix3d& K, const Eigen::Matrix3d& R,
                            const Eigen::Vector3d& t, const Eigen::Vector2d& centre,
                            double* error_px) {
  int c, r;
  double z;
  if (!other.Project(world, &c, &r, &z)) return false;
  const float other_depth = other.depth.At(r, c);
  if (!(other_depth > 0)) return false;
  // The exact (sub-pixel) projection is used, so that an exact surface reprojects exactly.
  const Eigen::Vector3d back = K * (R * other.SurfaceOnRay(world, z, other_depth) + t);
  if (!(back.z() > 0)) return false;
  *error_px = (back.head<2>() / back.z() - centre).norm();
  return true;
}

FloatMap FilterDepthMapByConsistency(const FusionView& ref,
                                     const std::vector<const FusionView*>& others,
                                     double max_reprojection_error_px, int min_consistent_views,
                                     double min_triangulation_angle_deg,
                                     ConsistencyFilterStats* stats) {
  FloatMap filtered = ref.depth;
  const double max_cos_angle = std::cos(min_triangulation_angle_deg * M_PI / 180);
  const Eigen::Vector3d ref_center = ref.Center();
  std::vector<Eigen::Vector3d> other_centers;
  for (const FusionView* other : others) other_centers.push_back(other->Center());
  const int width = ref.depth.Width(), height = ref.depth.Height();
  int64_t num_checked = 0, num_kept = 0;
#pragma omp parallel for schedule(dynamic, 8) reduction(+ : num_checked, num_kept)
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const float depth = ref.depth.At(row, col);
      if (!(depth > 0)) continue;
      ++num_checked;
      const Eigen::Vector3d world = ref.BackProject(col, row, depth);
      const Eigen::Vector2d centre = ref.PixelCentre(col, row);
      const Eigen::Vector3d to_ref = (ref_center - world).normalized();
      int consistent = 0;
      for (size_t v = 0; v < others.size(); ++v) {
        if (to_ref.dot((other_centers[v] - world).normalized()) > max_cos_angle) continue;
        double error_px;
        if (ForwardBackwardErrorPx(*others[v], world, ref.K, ref.R, ref.t, centre, &error_px) &&
            error_px <= max_reprojection_error_px) {
          ++consistent;
        }
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
