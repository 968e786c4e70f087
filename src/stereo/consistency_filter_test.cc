#include "src/stereo/consistency_filter.h"

#include <gtest/gtest.h>

#include "src/stereo/stereo_test_util.h"

namespace hairmvs {
namespace {

using testing_util::PlaneView;

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
  const FloatMap filtered = FilterDepthMapByConsistency(ref, {&left, &right}, 1.0, 1, 3.0, &stats);
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
  FilterDepthMapByConsistency(ref, {&left, &wrong}, 1.0, 1, 3.0, &one);
  const FloatMap none = FilterDepthMapByConsistency(ref, {&left, &wrong}, 1.0, 2, 3.0, &two);
  EXPECT_GT(one.num_kept, 40 * 60);
  EXPECT_EQ(two.num_kept, 0);
  for (float d : none.Data()) EXPECT_EQ(d, 0.0f);
  // No other view: nothing is consistent unless none is required.
  ConsistencyFilterStats zero;
  const FloatMap kept = FilterDepthMapByConsistency(ref, {}, 1.0, 0, 3.0, &zero);
  EXPECT_EQ(zero.num_kept, 80 * 60);
  EXPECT_EQ(kept.Data(), ref.depth.Data());
}

// A view beside the reference (0.5 degrees at the plane) reprojects any depth onto the pixel:
// with its map 30% too deep it still agrees everywhere, unless its triangulation angle must
// reach 3 degrees (COLMAP's filter_min_triangulation_angle); the views 5.7 degrees away count.
TEST(ConsistencyFilterTest, AViewBesideTheReferenceDoesNotCount) {
  const FusionView ref = PlaneView(Eigen::Vector3d(0, 0, 0), 0.0);
  FusionView beside = PlaneView(Eigen::Vector3d(0.0087, 0, 0), 0.0);
  for (float& d : beside.depth.Data()) d *= 1.3f;
  ConsistencyFilterStats any_angle, three_degrees;
  FilterDepthMapByConsistency(ref, {&beside}, 4.0, 1, 0.0, &any_angle);
  FilterDepthMapByConsistency(ref, {&beside}, 4.0, 1, 3.0, &three_degrees);
  EXPECT_GT(any_angle.num_kept, 70 * 60);
  EXPECT_EQ(three_degrees.num_kept, 0);
  const FusionView left = PlaneView(Eigen::Vector3d(-0.1, 0, 0), 0.1);
  ConsistencyFilterStats with_left;
  FilterDepthMapByConsistency(ref, {&beside, &left}, 4.0, 1, 3.0, &with_left);
  EXPECT_GT(with_left.num_kept, 40 * 60);
}

// Maps held cropped to their depths (FusionView::CropToDepth, as the geometric pass holds
// them) are filtered as the whole maps are, bit for bit: the reference's part of the result.
TEST(ConsistencyFilterTest, MapsCroppedToTheirDepthsAreFilteredAlike) {
  std::vector<FusionView> whole = {PlaneView(Eigen::Vector3d(0, 0, 0), 0.0),
                                   PlaneView(Eigen::Vector3d(-0.1, 0, 0), 0.1),
                                   PlaneView(Eigen::Vector3d(0.1, 0, 0), -0.1)};
  // A patch too far in the reference; each map's depths in a box of its own.
  for (int row = 20; row < 30; ++row) {
    for (int col = 30; col < 45; ++col) whole[0].depth.At(row, col) *= 1.3f;
  }
  const PixelBox boxes[] = {{11, 3, 60, 50}, {5, 9, 41, 47}, {30, 0, 50, 39}};
  for (size_t v = 0; v < whole.size(); ++v) {
    for (int row = 0; row < 60; ++row) {
      for (int col = 0; col < 80; ++col) {
        if (col < boxes[v].x0 || row < boxes[v].y0 || col >= boxes[v].x0 + boxes[v].width ||
            row >= boxes[v].y0 + boxes[v].height) {
          whole[v].depth.At(row, col) = 0.0f;
        }
      }
    }
  }
  std::vector<FusionView> cropped = whole;
  for (FusionView& view : cropped) view.CropToDepth();
  ASSERT_EQ(cropped[0].depth.Width(), 60);
  ConsistencyFilterStats whole_stats, cropped_stats;
  const FloatMap from_whole =
      FilterDepthMapByConsistency(whole[0], {&whole[1], &whole[2]}, 1.0, 1, 3.0, &whole_stats);
  const FloatMap from_cropped = FilterDepthMapByConsistency(
      cropped[0], {&cropped[1], &cropped[2]}, 1.0, 1, 3.0, &cropped_stats);
  EXPECT_EQ(cropped[0].Whole(from_cropped).Data(), from_whole.Data());
  EXPECT_EQ(cropped_stats.num_checked, whole_stats.num_checked);
  EXPECT_EQ(cropped_stats.num_kept, whole_stats.num_kept);
  // The boxes and the patch drop some depths and keep others.
  EXPECT_GT(whole_stats.num_kept, whole_stats.num_checked / 4);
  EXPECT_LT(whole_stats.num_kept, whole_stats.num_checked - 150);
}

}  // namespace
}  // namespace hairmvs
