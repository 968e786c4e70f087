#include "src/synthetic/renderer.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "src/core/depth_geometry.h"

namespace hairmvs {
namespace {

TEST(IntersectCapsule, BodyCapsAndMiss) {
  const Eigen::Vector3d a(-1, 0, 1), b(1, 0, 1);
  const Eigen::Vector3d o = Eigen::Vector3d::Zero();
  EXPECT_NEAR(IntersectCapsule(o, Eigen::Vector3d::UnitZ(), a, b, 0.1), 0.9, 1e-12);
  // Along the axis from the side: the cap at a, a radius before it.
  EXPECT_NEAR(IntersectCapsule(Eigen::Vector3d(-3, 0, 1), Eigen::Vector3d::UnitX(), a, b, 0.1),
              1.9, 1e-12);
  // Beyond the end but within the cap sphere.
  // Beyond the end but within the cap sphere: from (1.05, 0, 0) straight up, the cap at b.
  const double t = IntersectCapsule(Eigen::Vector3d(1.05, 0, 0), Eigen::Vector3d::UnitZ(), a,
                                    b, 0.1);
  ASSERT_GT(t, 0.0);
  EXPECT_NEAR((Eigen::Vector3d(1.05, 0, t) - b).norm(), 0.1, 1e-12);
  EXPECT_LT(IntersectCapsule(o, Eigen::Vector3d(1.2, 0, 1).normalized(), a, b, 0.1), 0.0);
  EXPECT_LT(IntersectCapsule(o, -Eigen::Vector3d::UnitZ(), a, b, 0.1), 0.0);
}

// Against ray marching: the first sample inside the capsule.
TEST(IntersectCapsule, MatchesRayMarching) {
  SplitMix64 rng(11);
  int hits = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Eigen::Vector3d a(rng.Uniform(-0.002, 0.002), rng.Uniform(-0.002, 0.002),
                            rng.Uniform(0.55, 0.65));
    const Eigen::Vector3d b = a + Eigen::Vector3d(rng.Uniform(-0.001, 0.001),
                                                  rng.Uniform(-0.001, 0.001),
                                                  rng.Uniform(-0.001, 0.001));
    const double r = 6e-5;
    // Aimed at a point near the segment, so about half the rays hit.
    const Eigen::Vector3d aim = a + rng.Uniform(-0.2, 1.2) * (b - a) +
                                Eigen::Vector3d(rng.Uniform(-1.5, 1.5) * r,
                                                rng.Uniform(-1.5, 1.5) * r, 0.0);
    const Eigen::Vector3d dir = aim.normalized();
    const double t = IntersectCapsule(Eigen::Vector3d::Zero(), dir, a, b, r);
    auto inside = [&](double s) {
      const Eigen::Vector3d x = s * dir;
      const Eigen::Vector3d ab = b - a;
      const double u = std::clamp((x - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      return (a + u * ab - x).norm() <= r;
    };
    double first = -1;
    for (double s = a.norm() - 0.002; s < a.norm() + 0.002; s += 2e-7) {
      if (inside(s)) {
        first = s;
        break;
      }
    }
    if (first < 0) {
      EXPECT_LT(t, 0.0) << trial;
    } else {
      ++hits;
      EXPECT_NEAR(t, first, 3e-7) << trial;
    }
  }
  EXPECT_GT(hits, 60);
}

// The piece of `strand` nearest to x.
int64_t NearestPiece(const DenseStrands& dense, int strand, const Eigen::Vector3d& x) {
  int64_t best = dense.offsets[strand];
  double best_d = std::numeric_limits<double>::infinity();
  for (int64_t i = dense.offsets[strand]; i + 1 < dense.offsets[strand + 1]; ++i) {
    const double d = DistanceToPolyline(dense.points, i, i + 2, x);
    if (d < best_d) best_d = d, best = i;
  }
  return best;
}

struct SmallScene {
  std::unique_ptr<HairScene> scene;
  std::vector<SyntheticView> views;
};

SmallScene MakeSmallScene(HairStyle style, int width = 160) {
  HairGenerationOptions options;
  options.style = style;
  options.num_strands = 2500;
  options.seed = 3;
  const HeadModel head;
  HairStrands hair = GenerateHair(head, options);
  SmallScene s;
  s.views = MakeGantryRig(1, hair.BoundingBoxCentre(), width);
  DenseStrands dense = DensifyStrands(hair, style == HairStyle::kCurly ? 8e-4 : 1.5e-3,
                                      1.6e-4, 0.8e-4);
  s.scene = std::make_unique<HairScene>(head, std::move(dense), hair.albedo, hair.layer,
                                        RenderSettings());
  return s;
}

// The rendered ground truth is the exact first hit through each pixel centre.
TEST(HairScene, GroundTruthIsFirstHitAtPixelCentres) {
  for (HairStyle style : {HairStyle::kStraight, HairStyle::kCurly}) {
  const SmallScene s = MakeSmallScene(style);
  const SyntheticView& view = s.views[0];
  const RenderedView r = s.scene->Render(view);
  int counts[3] = {0, 0, 0};
  for (int row = 0; row < view.height; row += 5) {
    for (int col = 0; col < view.width; col += 3) {
      const size_t p = static_cast<size_t>(row) * view.width + col;
      const RayHit hit = s.scene->CastRay(view, col + 0.5, row + 0.5);
      ASSERT_EQ(hit.label, r.label[p]) << row << " " << col;
      EXPECT_NEAR(hit.depth, r.depth.At(row, col), 1e-6);
      EXPECT_EQ(hit.strand, r.strand_id[p]);
      ++counts[hit.label];
    }
  }
  EXPECT_GT(counts[0], 50);
  EXPECT_GT(counts[2], 50);
  }
}

// A hair pixel's true depth, back-projected, lies on its strand's tube; projected into another
// view, the exact ray there finds the same strand at the same depth wherever nothing is in
// front, and that view's depth map agrees within a pixel where its pixels see that strand.
TEST(HairScene, CrossViewConsistency) {
  for (HairStyle style : {HairStyle::kStraight, HairStyle::kCurly}) {
    // 320 px: a pixel covers ~2.4 mm at 0.6 m, less than a curl's diameter.
    const SmallScene s = MakeSmallScene(style, 320);
    const DenseStrands& dense = s.scene->Strands();
    const SyntheticView& va = s.views[0];
    std::vector<RenderedView> renders;
    for (const auto& v : s.views) renders.push_back(s.scene->Render(v));
    int tested = 0, visible = 0, same_strand = 0, map_checked = 0, map_agree = 0;
    double max_tube_error = 0;
    for (int row = 0; row < va.height; row += 6) {
      for (int col = 0; col < va.width; col += 6) {
        const size_t p = static_cast<size_t>(row) * va.width + col;
        if (renders[0].label[p] != 2) continue;
        const int strand = renders[0].strand_id[p];
        const Eigen::Vector3d x = va.R.transpose() *
                                  (BackProjectPixel(va.K, col, row, renders[0].depth.At(row, col)) -
                                   va.t);
        const double d = DistanceToPolyline(dense.points, dense.offsets[strand],
                                            dense.offsets[strand + 1], x);
        // On the tube surface: the radius is at most 0.08 mm.
        EXPECT_LT(d, 8.1e-5);
        max_tube_error = std::max(max_tube_error, d);
        for (size_t j = 1; j < s.views.size(); ++j) {
          const SyntheticView& vb = s.views[j];
          const Eigen::Vector3d xc = vb.ToCamera(x);
          const Eigen::Vector2d xy = vb.Project(xc);
          if (xy.x() < 1 || xy.y() < 1 || xy.x() >= vb.width - 1 || xy.y() >= vb.height - 1) {
            continue;
          }
          ++tested;
          const RayHit hit = s.scene->CastRay(vb, xy.x(), xy.y());
          // Visible: nothing in front (a tube is ~0.1 mm thick, so the hit is within 0.2 mm).
          if (hit.label == 0 || hit.depth < xc.z() - 2e-4) continue;
          ++visible;
          if (hit.strand == strand) ++same_strand;
          // Pixels of view b next to the projection that see the same strand: their true depth
          // agrees with x's up to how fast the strand's depth changes over 1.5 pixels (steep
          // where the strand runs along the ray) plus the tube's thickness.
          // Curls can bring another part of the same strand into the neighbourhood: only the
          // part x is on (within a few pixels of arc length) is compared.
          const double footprint_m = xc.z() / vb.K(0, 0);
          const int64_t ia = NearestPiece(dense, strand, x);
          const Eigen::Vector3d tb =
              vb.R * (dense.points[ia + 1] - dense.points[ia]).cast<double>();
          const double slope = std::abs(tb.z()) / std::max(1e-3 * tb.norm(), tb.head<2>().norm());
          for (int dr = -1; dr <= 1; ++dr) {
            for (int dc = -1; dc <= 1; ++dc) {
              const int rb = static_cast<int>(xy.y()) + dr, cb = static_cast<int>(xy.x()) + dc;
              const size_t q = static_cast<size_t>(rb) * vb.width + cb;
              if (renders[j].strand_id[q] != strand) continue;
              const Eigen::Vector3d xb =
                  vb.R.transpose() *
                  (BackProjectPixel(vb.K, cb, rb, renders[j].depth.At(rb, cb)) - vb.t);
              const int64_t ib = NearestPiece(dense, strand, xb);
              double arc_m = 0;
              for (int64_t i = std::min(ia, ib); i < std::max(ia, ib); ++i) {
                arc_m += (dense.points[i + 1] - dense.points[i]).norm();
              }
              if (arc_m > 3.0 * footprint_m * std::sqrt(1.0 + slope * slope) + 2e-3) continue;
              ++map_checked;
              // The strand's depth changes by `slope` footprints per pixel moved across the
              // image (twice that, for the bending of curls), the tube adds its thickness.
              const double dist_px = (Eigen::Vector2d(cb + 0.5, rb + 0.5) - xy).norm();
              const double tolerance_m = 2.0 * (dist_px + 0.5) * footprint_m * slope + 2e-4;
              const bool agrees = std::abs(renders[j].depth.At(rb, cb) - xc.z()) < tolerance_m;
              map_agree += agrees;
            }
          }
        }
      }
    }
    ASSERT_GT(tested, 200);
    EXPECT_GT(visible, tested / 5);
    // The ray through the exact projection of a point on a strand's surface meets that strand
    // first unless the point is on the tube's far side from b (grazing) or a neighbour hides
    // it; almost all visible ones are the same strand.
    EXPECT_GT(same_strand, 0.9 * visible) << ToString(style);
    EXPECT_GT(map_checked, 20);
    // Curls bend within a pixel or two, where the linear slope bound above is loose.
    EXPECT_GE(map_agree, (style == HairStyle::kCurly ? 0.85 : 0.98) * map_checked)
        << ToString(style) << " " << map_agree << " of " << map_checked;
    RecordProperty("max_tube_error_m", std::to_string(max_tube_error));
  }
}

TEST(HairScene, RenderDoesNotDependOnThreads) {
  const SmallScene s = MakeSmallScene(HairStyle::kCurly);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const RenderedView one = s.scene->Render(s.views[2]);
  omp_set_num_threads(std::max(2, threads));
  const RenderedView many = s.scene->Render(s.views[2]);
  omp_set_num_threads(threads);
  EXPECT_EQ(one.rgb, many.rgb);
  EXPECT_EQ(one.depth.Data(), many.depth.Data());
  EXPECT_EQ(one.label, many.label);
  // Something was drawn: hair is darker than the grey background.
  int dark = 0;
  for (size_t p = 0; p < one.label.size(); ++p) dark += one.hair_opacity[p] > 0.5f;
  EXPECT_GT(dark, 100);
}

}  // namespace
}  // namespace hairmvs
