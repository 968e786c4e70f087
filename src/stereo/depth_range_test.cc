#include "src/stereo/depth_range.h"

#include <gtest/gtest.h>

#include <cmath>

#include "src/stereo/stereo_test_util.h"

namespace hairmvs {
namespace {

using testing_util::LookAtCamera;

const Eigen::Vector3d kCentre(0, 0, 1);
constexpr double kRadius = 0.1;

// Silhouette of the sphere: pixels whose ray (through the pixel centre) hits it.
FloatMap SphereMask(const StereoCamera& camera) {
  FloatMap mask(camera.width, camera.height, 1, 0.0f);
  const Eigen::Vector3d origin = camera.Center();
  const Eigen::Matrix3d K_inv = camera.K.inverse();
  for (int row = 0; row < camera.height; ++row) {
    for (int col = 0; col < camera.width; ++col) {
      const Eigen::Vector3d dir =
          (camera.R.transpose() * (K_inv * Eigen::Vector3d(col + 0.5, row + 0.5, 1)))
              .normalized();
      const Eigen::Vector3d oc = origin - kCentre;
      const double b = oc.dot(dir);
      const double disc = b * b - (oc.squaredNorm() - kRadius * kRadius);
      if (disc >= 0 && -b - std::sqrt(disc) > 0) mask.At(row, col) = 1;
    }
  }
  return mask;
}

struct Scene {
  StereoCamera ref;
  std::vector<std::pair<StereoCamera, FloatMap>> others;
};

// Reference `ref_distance` in front of the sphere's centre (at the origin by default) looking
// at it; others on a ring of radius `distance` around it.
Scene MakeScene(int num_others, double distance = 1, double ref_distance = 1) {
  Scene scene;
  scene.ref =
      LookAtCamera(kCentre - Eigen::Vector3d(0, 0, ref_distance), kCentre, 200, 160, 120);
  for (int i = 1; i <= num_others; ++i) {
    const double angle = 2 * M_PI * i / (num_others + 1);
    const Eigen::Vector3d centre =
        kCentre + distance * Eigen::Vector3d(std::sin(angle), 0.3 * std::cos(3 * angle),
                                             -std::cos(angle));
    const StereoCamera camera = LookAtCamera(centre, kCentre, 200, 160, 120);
    scene.others.emplace_back(camera, SphereMask(camera));
  }
  return scene;
}

TEST(DepthRangeTest, VisualHullRangeIsTightAroundTheSphere) {
  const Scene scene = MakeScene(7);
  double min_m = -1, max_m = -1;
  ASSERT_TRUE(VisualHullDepthRange(scene.ref, SphereMask(scene.ref), scene.others, 0.3, 5.0,
                                   &min_m, &max_m));
  // The sphere spans depths [0.9, 1.1] along the central ray; the hull contains the sphere
  // and, with 8 views around it, not much more. The 1st percentile trims the nearest samples
  // (only the central rays reach 0.9), the 5 mm margin brings them back.
  EXPECT_LE(min_m, 0.91);
  EXPECT_GE(min_m, 0.8);
  EXPECT_GE(max_m, 1.05);
  EXPECT_LE(max_m, 1.3);
}

// 3 x 3 maximum: a mask that keeps every pixel the sphere touches, not only those whose
// centre ray hits it (orientation_stereo dilates the masks for the same reason).
FloatMap Dilated(const FloatMap& mask) {
  FloatMap out(mask.Width(), mask.Height(), 1, 0.0f);
  for (int row = 0; row < mask.Height(); ++row) {
    for (int col = 0; col < mask.Width(); ++col) {
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const int r = row + dr, c = col + dc;
          if (r >= 0 && c >= 0 && r < mask.Height() && c < mask.Width() && mask.At(r, c) > 0) {
            out.At(row, col) = 1.0f;
          }
        }
      }
    }
  }
  return out;
}

VisualHullRangeOptions EveryPixel(bool find_far_ends) {
  VisualHullRangeOptions options;
  options.pixel_step = 1;
  options.find_far_ends = find_far_ends;
  return options;
}

TEST(DepthRangeTest, HullIntervalsStartInFrontOfTheSurface) {
  Scene scene = MakeScene(7);
  for (auto& view : scene.others) view.second = Dilated(view.second);
  const FloatMap mask = SphereMask(scene.ref);
  const FloatMap intervals =
      VisualHullIntervals(scene.ref, mask, scene.others, 0.3, 5.0, EveryPixel(true));
  ASSERT_EQ(intervals.Channels(), 2);
  const Eigen::Matrix3d K_inv = scene.ref.K.inverse();
  int rays = 0;
  std::vector<double> gaps;
  for (int row = 0; row < scene.ref.height; ++row) {
    for (int col = 0; col < scene.ref.width; ++col) {
      const float near_m = intervals.At(row, col, 0), far_m = intervals.At(row, col, 1);
      if (!(mask.At(row, col) > 0.5f)) {
        EXPECT_EQ(near_m, 0.0f);  // only the reference's masked pixels are sampled
        continue;
      }
      ASSERT_GT(near_m, 0.0f) << row << " " << col;
      ++rays;
      // The true z-depth where the ray enters the sphere (the reference sits at the origin
      // looking down +z, so camera and world frames agree).
      const Eigen::Vector3d ray = K_inv * Eigen::Vector3d(col + 0.5, row + 0.5, 1);
      const double a = ray.squaredNorm(), b = -ray.dot(kCentre);
      const double c = kCentre.squaredNorm() - kRadius * kRadius;
      const double disc = b * b - a * c;
      if (disc < 0) continue;  // a rim pixel: hit at its centre by the mask's normalised ray
      const double entry = (-b - std::sqrt(disc)) / a;
      // The hull contains the sphere: its first stretch starts at or before the surface (the
      // bisection resolves the transition to well under a millimetre) and ends behind it.
      EXPECT_LE(near_m, entry + 1e-3) << row << " " << col;
      EXPECT_GE(far_m, entry - 1e-3) << row << " " << col;
      gaps.push_back(entry - near_m);
    }
  }
  ASSERT_GT(rays, 100);
  std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
  // Eight views around it carve the hull close to the sphere's front.
  EXPECT_LT(gaps[gaps.size() / 2], 0.03);
  // Without the far ends: the same near ends, far channel 0.
  const FloatMap near_only =
      VisualHullIntervals(scene.ref, mask, scene.others, 0.3, 5.0, EveryPixel(false));
  for (size_t p = 0; p < near_only.NumPixels(); ++p) {
    EXPECT_EQ(near_only.Channel(0)[p], intervals.Channel(0)[p]);
    EXPECT_EQ(near_only.Channel(1)[p], 0.0f);
  }
}

TEST(DepthRangeTest, OneViewWithAWrongPoseCarvesOnlyTheStrictHull) {
  Scene scene = MakeScene(7);
  for (auto& view : scene.others) view.second = Dilated(view.second);
  // View 2's mask is 8 px off its pose (a wrong calibration: 2.3 degrees of rotation).
  const FloatMap right = scene.others[2].second;
  FloatMap shifted(right.Width(), right.Height(), 1, 0.0f);
  for (int row = 0; row < right.Height(); ++row) {
    for (int col = 0; col + 8 < right.Width(); ++col) shifted.At(row, col) = right.At(row, col + 8);
  }
  scene.others[2].second = shifted;
  const FloatMap mask = SphereMask(scene.ref);
  const Eigen::Matrix3d K_inv = scene.ref.K.inverse();
  // Rays whose hull entry lies more than 2 mm behind where they enter the sphere.
  auto carved_rays = [&](int min_carving_views) {
    VisualHullRangeOptions options = EveryPixel(false);
    options.min_carving_views = min_carving_views;
    const FloatMap intervals =
        VisualHullIntervals(scene.ref, mask, scene.others, 0.3, 5.0, options);
    int carved = 0;
    for (int row = 0; row < scene.ref.height; ++row) {
      for (int col = 0; col < scene.ref.width; ++col) {
        const Eigen::Vector3d ray = K_inv * Eigen::Vector3d(col + 0.5, row + 0.5, 1);
        const double a = ray.squaredNorm(), b = -ray.dot(kCentre);
        const double disc = b * b - a * (kCentre.squaredNorm() - kRadius * kRadius);
        if (!(mask.At(row, col) > 0.5f) || disc < 0) continue;
        const float near_m = intervals.At(row, col, 0);
        carved += !(near_m > 0) || near_m > (-b - std::sqrt(disc)) / a + 2e-3;
      }
    }
    return carved;
  };
  EXPECT_GT(carved_rays(1), 300);
  EXPECT_EQ(carved_rays(2), 0);
}

DepthRange Points(double min_m, double max_m, bool inside_mask) {
  DepthRange range;
  range.min_m = min_m;
  range.max_m = max_m;
  range.inside_mask = inside_mask;
  return range;
}

TEST(DepthRangeTest, HullAndPointsRangeKeepsTheHullWhenThePointsDisagree) {
  const Scene scene = MakeScene(7);
  const FloatMap mask = SphereMask(scene.ref);
  // The sphere lies at depths 0.9-1.1. All the view's points are far (a room): searched from
  // half their near end only, the hull would start behind the sphere's front.
  const DepthRange room = Points(2.0, 5.0, false);
  double min_m = 0, max_m = 0;
  ASSERT_TRUE(
      VisualHullDepthRange(scene.ref, mask, scene.others, 1.0, 10.0, &min_m, &max_m));
  EXPECT_GE(min_m, 1.0);
  // The points in the mask are wrong too (behind the sphere and beyond), but nearer than the
  // room's: the hull is searched from half their near end and kept as it is.
  HullRangeSource source = HullRangeSource::kPointsWithinHull;
  ASSERT_TRUE(HullAndPointsDepthRange(scene.ref, mask, scene.others, room,
                                      Points(0.7, 3.0, true), &min_m, &max_m, &source));
  EXPECT_EQ(source, HullRangeSource::kHull);
  EXPECT_LT(min_m, 0.9);
  EXPECT_GT(max_m, 1.1);
  EXPECT_LT(max_m - min_m, 0.5);
  // Points in the mask whose range lies within the hull's narrow it (a long T-group hull).
  ASSERT_TRUE(HullAndPointsDepthRange(scene.ref, mask, scene.others, room,
                                      Points(0.92, 1.08, true), &min_m, &max_m, &source));
  EXPECT_EQ(source, HullRangeSource::kPointsWithinHull);
  EXPECT_EQ(min_m, 0.92);
  EXPECT_EQ(max_m, 1.08);
  // Not from the mask (COLMAP's fallback to all points): never narrows.
  ASSERT_TRUE(HullAndPointsDepthRange(scene.ref, mask, scene.others, Points(0.6, 3.0, false),
                                      Points(0.92, 1.08, false), &min_m, &max_m, &source));
  EXPECT_EQ(source, HullRangeSource::kHull);
  EXPECT_LT(min_m, 0.9);
  // No points at all: no range.
  EXPECT_FALSE(HullAndPointsDepthRange(scene.ref, mask, scene.others, Points(-1, -1, false),
                                       Points(-1, -1, false), &min_m, &max_m, &source));
}

// Where the hull searched from `start` to `end` begins.
HullNearEnd NearEnd(const Scene& scene, const FloatMap& mask, double start, double end) {
  double min_m = 0, max_m = 0;
  HullNearEnd near_end;
  EXPECT_TRUE(VisualHullDepthRange(scene.ref, mask, scene.others, start, end, &min_m, &max_m,
                                   VisualHullRangeOptions(), &near_end));
  return near_end;
}

// Every point behind the sphere (on a room behind the head, say): searched from half their
// near end, no ray meets the hull (points from 2.5 m: the search starts at 1.25 m, behind the
// sphere) or the hull reaches the search's start (points in the mask from 1.9 m: it starts
// at 0.95 m, inside the sphere), so it is searched again nearer, where the masks cut the
// hull's near ends; points that lie within the hull found so do not narrow it.
TEST(DepthRangeTest, HullAndPointsRangeSearchesNearerWhenThePointsLieBehindTheHull) {
  const Scene scene = MakeScene(7);
  const FloatMap mask = SphereMask(scene.ref);
  EXPECT_TRUE(NearEnd(scene, mask, 0.95, 10.0).at_search_start);
  const HullNearEnd nearer = NearEnd(scene, mask, 0.3, 10.0);
  EXPECT_FALSE(nearer.at_search_start);
  EXPECT_GT(nearer.fraction_cut_by_masks, 0.9);
  double min_m = 0, max_m = 0;
  for (const DepthRange& in_mask :
       {Points(-1, -1, false), Points(2.5, 4.0, true), Points(1.9, 3.0, true)}) {
    HullRangeSource source = HullRangeSource::kHull;
    ASSERT_TRUE(HullAndPointsDepthRange(scene.ref, mask, scene.others, Points(2.5, 5.0, false),
                                        in_mask, &min_m, &max_m, &source));
    EXPECT_EQ(source, HullRangeSource::kHullInFrontOfPoints);
    EXPECT_LT(min_m, 0.9);
    EXPECT_GT(min_m, 0.8);
    EXPECT_GT(max_m, 1.05);
    EXPECT_LT(max_m, 1.3);
  }
}

// Masks that keep whole images carve nothing: searched nearer, only the views' frusta would
// cut the hull's near ends (up to where they meet, near the views), so the first search's
// range stands.
// The range of an estimate: the 1st to 99th percentile of its depths (the strays beyond left
// out), widened by the margin factor both ways; too few depths give none.
TEST(DepthRangeTest, RangeOfAnEstimateSpansItsDepthsWithAMargin) {
  FloatMap depth(50, 40, 1, 0.0f);  // 2000 pixels: 1000 depths from 0.5 to 0.6 m, 2 strays
  for (int i = 0; i < 1000; ++i) depth.Data()[2 * i] = 0.5f + 0.1f * i / 999.0f;
  depth.Data()[1] = 0.05f;
  depth.Data()[3] = 9.0f;
  double min_m = 0, max_m = 0;
  ASSERT_TRUE(DepthRangeOfEstimate(depth, 1.2, 100, &min_m, &max_m));
  // Of the 1002 depths sorted, the 1st percentile is index floor(0.01 * 1001) = 10, 0.5 + 0.1 *
  // 9 / 999 (after the stray at 0.05 m), the 99th index 990, 0.5 + 0.1 * 989 / 999.
  EXPECT_NEAR(min_m, (0.5 + 0.1 * 9 / 999.0) / 1.2, 1e-6);
  EXPECT_NEAR(max_m, (0.5 + 0.1 * 989 / 999.0) * 1.2, 1e-6);
  min_m = max_m = -1;
  EXPECT_FALSE(DepthRangeOfEstimate(depth, 1.2, 1003, &min_m, &max_m));
  EXPECT_EQ(min_m, -1);
  EXPECT_FALSE(DepthRangeOfEstimate(FloatMap(4, 4, 1, 0.0f), 1.2, 1, &min_m, &max_m));
}

TEST(DepthRangeTest, MasksThatCarveNothingAreNotSearchedNearer) {
  Scene scene = MakeScene(7);
  const FloatMap mask = SphereMask(scene.ref);
  for (auto& view : scene.others) view.second = FloatMap(160, 120, 1, 1.0f);
  EXPECT_TRUE(NearEnd(scene, mask, 1.25, 10.0).at_search_start);
  const HullNearEnd nearer = NearEnd(scene, mask, 1.25 / 64, 10.0);
  EXPECT_FALSE(nearer.at_search_start);
  EXPECT_EQ(nearer.fraction_cut_by_masks, 0.0);
  double first_min = 0, first_max = 0, min_m = 0, max_m = 0;
  ASSERT_TRUE(VisualHullDepthRange(scene.ref, mask, scene.others, 1.25, 10.0, &first_min,
                                   &first_max));
  HullRangeSource source = HullRangeSource::kHullInFrontOfPoints;
  ASSERT_TRUE(HullAndPointsDepthRange(scene.ref, mask, scene.others, Points(2.5, 5.0, false),
                                      Points(-1, -1, false), &min_m, &max_m, &source));
  EXPECT_EQ(source, HullRangeSource::kHull);
  EXPECT_EQ(min_m, first_min);
  EXPECT_EQ(max_m, first_max);
}

// A close-up (the reference 0.15 m from the sphere's front, the others on a ring of 0.4 m)
// with its points on the sphere's front: the views' cones meet in front of the search's start,
// so that the hull reaches it, but the points overlap the hull's range: the range they narrow
// it to stands (searched nearer, the hull would run up to 0.02 m).
TEST(DepthRangeTest, ACloseUpWithPointsInItsHullIsNotSearchedNearer) {
  const Scene scene = MakeScene(7, 0.4, 0.25);
  const FloatMap mask = SphereMask(scene.ref);
  EXPECT_TRUE(NearEnd(scene, mask, 0.075, 0.5).at_search_start);
  double min_m = 0, max_m = 0;
  HullRangeSource source = HullRangeSource::kHullInFrontOfPoints;
  ASSERT_TRUE(HullAndPointsDepthRange(scene.ref, mask, scene.others, Points(0.15, 0.25, true),
                                      Points(0.15, 0.25, true), &min_m, &max_m, &source));
  EXPECT_EQ(source, HullRangeSource::kPointsWithinHull);
  EXPECT_EQ(min_m, 0.15);
  EXPECT_EQ(max_m, 0.25);
}

TEST(DepthRangeTest, ViewsThatDoNotSeeThePointDoNotVeto) {
  Scene scene = MakeScene(7);
  const FloatMap ref_mask = SphereMask(scene.ref);
  double min_a = -1, max_a = -1, min_b = -1, max_b = -1;
  ASSERT_TRUE(
      VisualHullDepthRange(scene.ref, ref_mask, scene.others, 0.3, 5.0, &min_a, &max_a));
  // A view looking away from the sphere with an empty mask: nothing projects into it.
  const StereoCamera away =
      LookAtCamera(Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(0, 0, 5), 200, 160, 120);
  scene.others.emplace_back(away, FloatMap(160, 120, 1, 0.0f));
  ASSERT_TRUE(
      VisualHullDepthRange(scene.ref, ref_mask, scene.others, 0.3, 5.0, &min_b, &max_b));
  EXPECT_DOUBLE_EQ(min_a, min_b);
  EXPECT_DOUBLE_EQ(max_a, max_b);
  // A view with the sphere in front of it but outside its frame (45 degrees off its axis, its
  // half field of view 22 degrees), with an empty mask: the points project beside the frame,
  // not onto its border pixels.
  const StereoCamera beside =
      LookAtCamera(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 1), 200, 160, 120);
  const Eigen::Vector3d centre_in_beside = beside.R * kCentre + beside.t;
  ASSERT_GT(centre_in_beside.z(), 0);
  scene.others.emplace_back(beside, FloatMap(160, 120, 1, 0.0f));
  ASSERT_TRUE(
      VisualHullDepthRange(scene.ref, ref_mask, scene.others, 0.3, 5.0, &min_b, &max_b));
  EXPECT_DOUBLE_EQ(min_a, min_b);
  EXPECT_DOUBLE_EQ(max_a, max_b);
}

TEST(DepthRangeTest, NoRangeWhenTheViewsSeeingTheRaysExcludeEverything) {
  Scene scene = MakeScene(3);
  for (auto& view : scene.others) view.second = FloatMap(160, 120, 1, 0.0f);
  double min_m = -1, max_m = -1;
  EXPECT_FALSE(VisualHullDepthRange(scene.ref, SphereMask(scene.ref), scene.others, 0.3, 5.0,
                                    &min_m, &max_m));
  EXPECT_EQ(min_m, -1);
  // And with no other view nothing constrains the rays: no range either.
  EXPECT_FALSE(VisualHullDepthRange(scene.ref, SphereMask(scene.ref), {}, 0.3, 5.0, &min_m,
                                    &max_m));
}

}  // namespace
}  // namespace hairmvs
