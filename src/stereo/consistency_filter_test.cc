#include "src/stereo/consistency_filter.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "src/stereo/depth_estimator.h"

namespace hairmvs {
namespace {

// A camera at `center` looking at the origin along +z-ish (no roll), and the exact z-depth map
// of the world plane z_world = 1 seen by it (all cameras sit at z_world = 0 and look up +z).
FusionView PlaneView(const Eigen::Vector3d& center, double yaw_rad) {
  FusionView view;
  view.K << 100, 0, 40, 0, 100, 30, 0, 0, 1;
  view.R = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitY()).toRotationMatrix().transpose();
  view.t = -view.R * center;
  view.depth = FloatMap(80, 60, 1, 0.0f);
  const Eigen::Matrix3d K_inv = view.K.inverse();
  for (int row = 0; row < 60; ++row) {
    for (int col = 0; col < 80; ++col) {
      // Ray in world coordinates; intersect z_world = 1.
      const Eigen::Vector3d ray_cam = K_inv * Eigen::Vector3d(col + 0.5, row + 0.5, 1.0);
      const Eigen::Vector3d ray = view.R.transpose() * ray_cam;
      const double s = (1.0 - center.z()) / ray.z();
      view.depth.At(row, col) = static_cast<float>(s * ray_cam.z());
    }
  }
  return view;
}

TEST(ConsistencyFilterTest, KeepsAgreeingDepthsAndDropsAWrongPatch) {
  const FusionView left = PlaneView(Eigen::Vector3d(-0.1, 0, 0), 0.1);
  FusionView ref = PlaneView(Eigen::Vector3d(0, 0, 0), 0.0);
  const FusionView right = PlaneView(Eigen::Vector3d(0.1, 0, 0), -0.1);
  // A patch 30% too far (about 2 px of disparity), as a match on a hair layer behind the
  // surface would be.
  for (int row = 20; row < 30; ++row) {
    for (int col = 30; col < 45; ++col) ref.depth.At(row, col) *= 1.3f;
  }
  ConsistencyFilterStats stats;
  const FloatMap filtered = FilterDepthMapByConsistency(ref, {&left, &right}, 1.0, 1, &stats);
  EXPECT_EQ(stats.num_checked, 80 * 60);
  for (int row = 20; row < 30; ++row) {
    for (int col = 30; col < 45; ++col) EXPECT_EQ(filtered.At(row, col), 0.0f);
  }
  // Away from the patch every pixel that a neighbour sees keeps its exact depth: the yawed
  // neighbours see the whole centre of the reference.
  for (int row = 0; row < 60; ++row) {
    for (int col = 20; col < 60; ++col) {
      if (row >= 20 && row < 30 && col >= 30 && col < 45) continue;
      EXPECT_EQ(filtered.At(row, col), ref.depth.At(row, col)) << row << " " << col;
    }
  }
  EXPECT_LE(stats.num_kept, 80 * 60 - 150);
  EXPECT_GE(stats.num_kept, 40 * 60 - 150);
}

TEST(ConsistencyFilterTest, NeedsTheRequiredNumberOfAgreeingViews) {
  const FusionView ref = PlaneView(Eigen::Vector3d(0, 0, 0), 0.0);
  const FusionView left = PlaneView(Eigen::Vector3d(-0.1, 0, 0), 0.1);
  FusionView wrong = PlaneView(Eigen::Vector3d(0.1, 0, 0), -0.1);
  for (float& d : wrong.depth.Data()) d *= 0.7f;  // ~4 px off everywhere
  ConsistencyFilterStats one, two;
  FilterDepthMapByConsistency(ref, {&left, &wrong}, 1.0, 1, &one);
  const FloatMap none = FilterDepthMapByConsistency(ref, {&left, &wrong}, 1.0, 2, &two);
  EXPECT_GT(one.num_kept, 40 * 60);
  EXPECT_EQ(two.num_kept, 0);
  for (float d : none.Data()) EXPECT_EQ(d, 0.0f);
  // No other view: nothing is consistent unless none is required.
  ConsistencyFilterStats zero;
  const FloatMap kept = FilterDepthMapByConsistency(ref, {}, 1.0, 0, &zero);
  EXPECT_EQ(zero.num_kept, 80 * 60);
  EXPECT_EQ(kept.Data(), ref.depth.Data());
}

// The geometric pass's prior (src/stereo/depth_estimator.h) uses the same forward-backward error:
// 0 at the depth the other views' maps agree with, the most where they disagree by the maximum
// error or do not see the point.
TEST(GeometricPriorTest, IsLowestAtTheDepthTheOtherMapsAgreeWith) {
  const FusionView ref = PlaneView(Eigen::Vector3d(0, 0, 0), 0.0);
  const FusionView left = PlaneView(Eigen::Vector3d(-0.1, 0, 0), 0.1);
  FusionView blind = PlaneView(Eigen::Vector3d(0.1, 0, 0), -0.1);
  for (float& d : blind.depth.Data()) d = 0.0f;  // no depth anywhere
  StereoCamera camera;
  camera.K = ref.K;
  camera.R = ref.R;
  camera.t = ref.t;
  camera.width = ref.depth.Width();
  camera.height = ref.depth.Height();
  const DepthLabels labels(0.5, 2.0, 64, /*inverse=*/true);
  const size_t n = static_cast<size_t>(camera.width) * camera.height;
  GeometricPrior prior;
  prior.views = {&left, &blind};
  prior.weight = 2.0;
  prior.max_error_px = 3.0;
  std::vector<float> volume(n * labels.num_labels, 0.0f);
  AddGeometricPrior(prior, camera, 1.0, labels, {}, 1.0f, labels.num_labels, 0.5f, &volume);
  int checked = 0;
  for (int row = 0; row < camera.height; ++row) {
    for (int col = 20; col < 60; ++col) {  // the part of the reference the left view sees
      const size_t p = static_cast<size_t>(row) * camera.width + col;
      int best = 0;
      for (int k = 1; k < labels.num_labels; ++k) {
        if (volume[k * n + p] < volume[best * n + p]) best = k;
      }
      const double true_label = labels.Label(ref.depth.At(row, col));
      EXPECT_LE(std::abs(best - true_label), 1.0) << row << " " << col;
      // weight * scale = 1 over the two views: the blind one always adds 0.5, the left one
      // nearly nothing at the true depth and 0.5 at labels far from it.
      EXPECT_NEAR(volume[best * n + p], 0.5f, 0.1f);
      EXPECT_FLOAT_EQ(volume[0 * n + p], 1.0f);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 40 * 60);
  // Labels relative to a per-pixel base (the fine band) score the same depths alike.
  std::vector<float> base(n, 10.0f), band(n * 8, 0.0f);
  AddGeometricPrior(prior, camera, 1.0, labels, base, 0.5f, 8, 0.5f, &band);
  for (int k = 0; k < 8; ++k) {
    const size_t p = 30 * camera.width + 40;
    std::vector<float> single(n, 0.0f);
    const std::vector<float> one_base(n, 10.0f + 0.5f * k);
    AddGeometricPrior(prior, camera, 1.0, labels, one_base, 1.0f, 1, 0.5f, &single);
    EXPECT_FLOAT_EQ(band[k * n + p], single[p]) << k;
  }
}

}  // namespace
}  // namespace hairmvs
