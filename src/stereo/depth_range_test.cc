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

// Reference at the origin looking at the sphere; others on a ring of radius 1 around it.
Scene MakeScene(int num_others) {
  Scene scene;
  scene.ref = LookAtCamera(Eigen::Vector3d::Zero(), kCentre, 200, 160, 120);
  for (int i = 1; i <= num_others; ++i) {
    const double angle = 2 * M_PI * i / (num_others + 1);
    const Eigen::Vector3d centre =
        kCentre + Eigen::Vector3d(std::sin(angle), 0.3 * std::cos(3 * angle), -std::cos(angle));
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
