#include "src/synthetic/hair_model.h"

#include <gtest/gtest.h>

#include <limits>

#include "src/core/logging.h"
#include "src/core/test_util.h"
#include "src/evaluation/ground_truth.h"

namespace hairmvs {
namespace {

TEST(SplitMix64, DeterministicAndInRange) {
  SplitMix64 a(42), b(42), c(43);
  bool differs = false;
  for (int i = 0; i < 1000; ++i) {
    const double x = a.Uniform();
    EXPECT_EQ(x, b.Uniform());
    differs |= x != c.Uniform();
    EXPECT_GE(x, 0.0);
    EXPECT_LT(x, 1.0);
  }
  EXPECT_TRUE(differs);
  EXPECT_NE(DeriveSeed(1, 1, 0), DeriveSeed(1, 1, 1));
  EXPECT_NE(DeriveSeed(1, 1, 0), DeriveSeed(2, 1, 0));
}

TEST(HeadModel, IntersectAndNormal) {
  HeadModel head;
  // From +Y straight at the centre: hits the back of the head at y = b.
  const double t = head.Intersect(Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0, -1, 0));
  EXPECT_NEAR(t, 1.0 - 0.10, 1e-12);
  EXPECT_LT(head.Intersect(Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0, 1, 0)), 0.0);
  EXPECT_TRUE(head.Normal(Eigen::Vector3d(0, 0, 0.11)).isApprox(Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(head.ShellValue(Eigen::Vector3d(0.08, 0, 0), 0.0), 1.0, 1e-12);
}

HairStrands SmallHair(HairStyle style, uint64_t seed) {
  HairGenerationOptions options;
  options.style = style;
  options.num_strands = 300;
  options.seed = seed;
  return GenerateHair(HeadModel(), options);
}

TEST(GenerateHair, RootsOnScalpPointsOutsideHeadDeterministic) {
  const HeadModel head;
  for (HairStyle style : {HairStyle::kStraight, HairStyle::kCurly}) {
    const HairStrands hair = SmallHair(style, 7);
    ASSERT_EQ(hair.NumStrands(), 300);
    ASSERT_EQ(hair.offsets.back(), static_cast<int64_t>(hair.points.size()));
    for (int s = 0; s < hair.NumStrands(); ++s) {
      ASSERT_GT(hair.offsets[s + 1] - hair.offsets[s], 10);
      const Eigen::Vector3d root = hair.points[hair.offsets[s]].cast<double>();
      EXPECT_NEAR(head.ShellValue(root, 0.0), 1.0, 1e-5);
      // Roots on the upper part: not below the nape's hairline.
      EXPECT_GT(root.z(), -0.05);
      for (int64_t i = hair.offsets[s] + 1; i < hair.offsets[s + 1]; ++i) {
        EXPECT_GE(head.ShellValue(hair.points[i].cast<double>(), 0.0), 1.0 - 1e-4);
      }
      // Hair falls: the tip is below the root.
      EXPECT_LT(hair.points[hair.offsets[s + 1] - 1].z(), root.z());
    }
    const HairStrands again = SmallHair(style, 7);
    EXPECT_EQ(again.points, hair.points);
    const HairStrands other = SmallHair(style, 8);
    EXPECT_NE(other.points, hair.points);
  }
}

// Given strands: layers from their height above the scalp on GenerateHair's scale (1 + 14 *
// layer mm), dark-brown albedos from the seed; offsets that do not cover the points throw.
TEST(HairFromStrands, LayersFromHeightAboveScalpAndSeededAlbedo) {
  const HeadModel head;  // the top of the head at z = 0.11
  std::vector<Eigen::Vector3f> points;
  std::vector<int64_t> offsets = {0};
  for (double height : {0.0, 0.008, 0.030}) {
    for (int k = 0; k < 5; ++k) {  // a short strand at that height over the crown
      points.emplace_back(0.001f * k, 0.0f, static_cast<float>(0.11 + height));
    }
    offsets.push_back(static_cast<int64_t>(points.size()));
  }
  const HairStrands hair = HairFromStrands(head, points, offsets, 3);
  ASSERT_EQ(hair.NumStrands(), 3);
  EXPECT_EQ(hair.points, points);
  EXPECT_EQ(hair.offsets, offsets);
  EXPECT_FLOAT_EQ(hair.layer[0], 0.0f);  // on the scalp: below the lowest layer, clamped
  EXPECT_NEAR(hair.layer[1], 0.5, 0.01);  // (8 - 1) / 14
  EXPECT_FLOAT_EQ(hair.layer[2], 1.0f);  // 30 mm up: above the outermost layer, clamped
  for (const Eigen::Vector3f& albedo : hair.albedo) {
    EXPECT_GT(albedo.x(), albedo.y());
    EXPECT_GT(albedo.y(), albedo.z());
    EXPECT_LT(albedo.x(), 0.07f);
    EXPECT_GT(albedo.z(), 0.005f);
  }
  EXPECT_NE(hair.albedo[0], hair.albedo[1]);
  EXPECT_EQ(HairFromStrands(head, points, offsets, 3).albedo, hair.albedo);
  EXPECT_NE(HairFromStrands(head, points, offsets, 4).albedo, hair.albedo);

  const std::vector<int64_t> short_of_the_points = {0, 5, 10};  // 15 points
  EXPECT_THROW(HairFromStrands(head, points, short_of_the_points, 3), Error);
  const std::vector<int64_t> one_point_strand = {0, 1, 10, 15};
  EXPECT_THROW(HairFromStrands(head, points, one_point_strand, 3), Error);
  // A point far from the head (another unit, a stray value), or not finite, is named: it would
  // be densified into billions of points.
  for (const float far : {1e4f, std::numeric_limits<float>::infinity(),
                          std::numeric_limits<float>::quiet_NaN()}) {
    std::vector<Eigen::Vector3f> stray = points;
    stray[7].x() = far;
    const std::string error =
        testing_util::ErrorOf([&] { HairFromStrands(head, stray, offsets, 3); });
    EXPECT_NE(error.find("HairFromStrands: point 7 ("), std::string::npos) << error;
    EXPECT_NE(error.find("within 2 m of it"), std::string::npos) << error;
  }
}

// Curls make a strand much longer than the distance it covers.
TEST(GenerateHair, CurlyIsTortuous) {
  auto tortuosity = [](const HairStrands& hair) {
    double length = 0, span = 0;
    for (int s = 0; s < hair.NumStrands(); ++s) {
      for (int64_t i = hair.offsets[s]; i + 1 < hair.offsets[s + 1]; ++i) {
        length += (hair.points[i + 1] - hair.points[i]).norm();
      }
      span += (hair.points[hair.offsets[s + 1] - 1] - hair.points[hair.offsets[s]]).norm();
    }
    return length / span;
  };
  const double straight = tortuosity(SmallHair(HairStyle::kStraight, 3));
  const double curly = tortuosity(SmallHair(HairStyle::kCurly, 3));
  EXPECT_LT(straight, 1.6);
  EXPECT_GT(curly, straight + 0.5);
}

TEST(DensifyStrands, KeepsStoredPointsFollowsSplineAndTapers) {
  const HairStrands hair = SmallHair(HairStyle::kCurly, 5);
  const double spacing = 0.0008;
  const DenseStrands dense = DensifyStrands(hair, spacing, 1.6e-4, 0.8e-4);
  ASSERT_EQ(dense.offsets.size(), hair.offsets.size());
  for (int s = 0; s < hair.NumStrands(); s += 17) {
    // Every stored point is a dense point, in order.
    int64_t j = dense.offsets[s];
    for (int64_t i = hair.offsets[s]; i < hair.offsets[s + 1]; ++i) {
      while (j < dense.offsets[s + 1] && dense.points[j] != hair.points[i]) ++j;
      ASSERT_LT(j, dense.offsets[s + 1]) << "stored point " << i << " missing";
    }
    EXPECT_NEAR(dense.radius_m[dense.offsets[s]], 0.8e-4, 1e-9);
    EXPECT_NEAR(dense.radius_m[dense.offsets[s + 1] - 1], 0.4e-4, 1e-9);
    for (int64_t k = dense.offsets[s]; k + 1 < dense.offsets[s + 1]; ++k) {
      EXPECT_EQ(dense.strand[k], s);
      EXPECT_LT((dense.points[k + 1] - dense.points[k]).norm(), 2.0 * spacing);
    }
  }
  // The dense points lie on the uniform Catmull-Rom spline of the evaluation code (its ends'
  // neighbours repeated): every segment's midpoint on the spline lies on the dense polyline,
  // while the chord's midpoint, which linear densification would give, is often off it.
  int segments = 0, chord_off = 0;
  double worst = 0;
  for (int s = 0; s < hair.NumStrands(); s += 17) {
    const int64_t first = hair.offsets[s], last = hair.offsets[s + 1] - 1;
    auto point = [&](int64_t i) {
      return hair.points[std::clamp(i, first, last)].cast<double>();
    };
    for (int64_t i = first; i < last; ++i) {
      const Eigen::Vector3d on_spline =
          CatmullRom(point(i - 1), point(i), point(i + 1), point(i + 2), 0.5);
      worst = std::max(worst, DistanceToPolyline(dense.points, dense.offsets[s],
                                                 dense.offsets[s + 1], on_spline));
      chord_off += (0.5 * (point(i) + point(i + 1)) - on_spline).norm() > 1e-4;
      ++segments;
    }
  }
  ASSERT_GT(segments, 100);
  EXPECT_LT(worst, 2e-5);
  EXPECT_GT(chord_off, segments / 4);
  // A spacing that would take more points than memory holds is refused before any is made.
  const std::string error =
      testing_util::ErrorOf([&] { DensifyStrands(hair, 1e-12, 1e-4, 1e-4); });
  EXPECT_NE(error.find("points at one per 1e-12 m"), std::string::npos) << error;
}

}  // namespace
}  // namespace hairmvs
