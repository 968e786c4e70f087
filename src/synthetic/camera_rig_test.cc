#include "src/synthetic/camera_rig.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

namespace hairmvs {
namespace {

// synth_straight_gantry's g0_c (sparse/images.txt) and hair centre (gt/cameras.npz).
TEST(MakeGantryRig, MatchesSharedSetPose) {
  const Eigen::Vector3d hair_centre(-0.0016130916774272919, 0.00971873477101326,
                                    -0.07366371154785156);
  const auto views = MakeGantryRig(8, hair_centre, 960);
  ASSERT_EQ(views.size(), 32u);
  EXPECT_EQ(views[0].name, "g0_c.png");
  EXPECT_EQ(views[0].height, 640);
  EXPECT_NEAR(views[0].K(0, 0), 767.783, 1e-9);
  EXPECT_NEAR(views[0].K(0, 2), 480.0, 1e-12);
  EXPECT_NEAR(views[0].K(1, 2), 320.0, 1e-12);
  const Eigen::Quaterniond q(0, 0, -0.73727733680989826, 0.67559020761590682);
  EXPECT_LT((views[0].R - q.toRotationMatrix()).norm(), 1e-6);
  EXPECT_LT((views[0].t - Eigen::Vector3d(-0.001613091677, -0.074230442433, 0.603261536558))
                .norm(),
            1e-6);
  // g3_l.png
  const Eigen::Quaterniond q3(0.040244043349002181, 0.077308087991004193, 0.88363548916204782,
                              -0.45999152035602492);
  EXPECT_EQ(views[13].name, "g3_l.png");
  EXPECT_LT((views[13].R - q3.toRotationMatrix()).norm(), 1e-6);
}

TEST(MakeGantryRig, TGroupGeometry) {
  const Eigen::Vector3d target(0.0, 0.01, -0.07);
  const auto views = MakeGantryRig(2, target, 480);
  ASSERT_EQ(views.size(), 8u);
  for (const auto& v : views) {
    EXPECT_NEAR((v.Centre() - target).norm(), 0.6, 1e-12);
    EXPECT_TRUE(v.R.isUnitary(1e-12));
    EXPECT_NEAR(v.R.determinant(), 1.0, 1e-12);
    // The target is at the principal point; world up is image up (-y).
    const Eigen::Vector2d xy = v.Project(v.ToCamera(target));
    EXPECT_NEAR(xy.x(), v.K(0, 2), 1e-9);
    EXPECT_NEAR(xy.y(), v.K(1, 2), 1e-9);
    EXPECT_LT((v.R * Eigen::Vector3d::UnitZ()).y(), 0.0);
  }
  auto angle_deg = [&](int a, int b) {
    const Eigen::Vector3d da = views[a].Centre() - target, db = views[b].Centre() - target;
    return std::acos(da.normalized().dot(db.normalized())) * 180.0 / M_PI;
  };
  EXPECT_EQ(views[1].name, "g0_l.png");
  EXPECT_NEAR(views[1].az_deg - views[0].az_deg, -10.0, 1e-12);
  EXPECT_NEAR(views[2].az_deg - views[0].az_deg, 10.0, 1e-12);
  EXPECT_NEAR(views[3].el_deg - views[0].el_deg, -10.0, 1e-12);
  EXPECT_NEAR(angle_deg(0, 3), 10.0, 1e-9);
  // Group 0 looks at the back of the head (+Y): the face is at -Y.
  EXPECT_GT(views[0].Centre().y(), 0.5);
}

TEST(MakeHandheldRig, VariedAndDeterministic) {
  const Eigen::Vector3d target(0.0, 0.01, -0.07);
  const auto views = MakeHandheldRig(12, target, 400, 3);
  const auto again = MakeHandheldRig(12, target, 400, 3);
  ASSERT_EQ(views.size(), 12u);
  EXPECT_EQ(views[0].name, "h00.png");
  double min_d = 1, max_d = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    const double d = (views[i].Centre() - target).norm();
    min_d = std::min(min_d, d);
    max_d = std::max(max_d, d);
    EXPECT_GE(d, 0.45 - 1e-9);
    EXPECT_LE(d, 0.8 + 1e-9);
    EXPECT_LE(std::abs(views[i].roll_deg), 6.0);
    EXPECT_TRUE(views[i].R.isApprox(again[i].R));
    // The head is in view.
    const Eigen::Vector2d xy = views[i].Project(views[i].ToCamera(target));
    EXPECT_GT(xy.x(), 0.3 * views[i].width);
    EXPECT_LT(xy.x(), 0.7 * views[i].width);
  }
  EXPECT_GT(max_d - min_d, 0.1);
}

}  // namespace
}  // namespace hairmvs
