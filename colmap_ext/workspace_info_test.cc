#include "colmap_ext/workspace_info.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "colmap_ext/test_util.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace hairmvs {
namespace {

TEST(WorkspaceInfo, SyntheticWorkspace) {
  const std::string dir = testing_util::MakeTestDir("info");
  testing_util::PlaneModelOptions options;
  options.plane_z_m = 2.0;
  options.centres = {{0, 0, 0}, {-0.1, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}};
  testing_util::WriteTestWorkspace(dir, testing_util::MakePlaneModel(options));
  CreateDirs(JoinPaths(dir, "masks"));
  cv::Mat mask(48, 64, CV_8U, cv::Scalar(0));
  mask(cv::Rect(0, 0, 32, 48)).setTo(255);
  ASSERT_TRUE(cv::imwrite(JoinPaths(dir, "masks", "a.png.png"), mask));

  const WorkspaceInfo info = ComputeWorkspaceInfo(dir, "", SourceViewOptions());
  ASSERT_EQ(info.views.size(), 4u);
  EXPECT_EQ(info.views[0].mask_path, JoinPaths(dir, "masks", "a.png.png"));
  EXPECT_DOUBLE_EQ(info.views[0].mask_keep_fraction, 0.5);
  EXPECT_TRUE(info.views[1].mask_path.empty());
  EXPECT_GT(info.views[0].depth_range.min_m, 0);
  EXPECT_EQ(info.selections.size(), 4u);
  EXPECT_EQ(info.num_t_groups, 1);
  const std::string report = info.Report();
  for (const char* part : {"4 views", "PINHOLE 64x48", "fx 50", "[T group]", "why:",
                           "mask 0.500", "workspace_info took"}) {
    EXPECT_NE(report.find(part), std::string::npos) << part << "\n" << report;
  }

  // Unusable masks are listed with the reason, not a stop of the report.
  ASSERT_TRUE(cv::imwrite(JoinPaths(dir, "masks", "b.png.png"), cv::Mat(48, 64, CV_8U, 0.0)));
  ASSERT_TRUE(cv::imwrite(JoinPaths(dir, "masks", "c.png.png"), cv::Mat(20, 64, CV_8U, 255.0)));
  const WorkspaceInfo bad = ComputeWorkspaceInfo(dir, "", SourceViewOptions());
  EXPECT_TRUE(bad.views[0].mask_error.empty());
  EXPECT_NE(bad.views[1].mask_error.find("excludes every pixel"), std::string::npos);
  EXPECT_NE(bad.views[2].mask_error.find("aspect ratio"), std::string::npos);
  EXPECT_EQ(bad.views[2].mask_keep_fraction, -1);
  const std::string bad_report = bad.Report();
  for (const char* part : {"mask UNUSABLE", "Unusable mask: Mask ", "c.png.png is 64 x 20"}) {
    EXPECT_NE(bad_report.find(part), std::string::npos) << part << "\n" << bad_report;
  }
  // So are images of another size than their camera's (resized after the undistorter).
  EXPECT_TRUE(bad.views[3].image_error.empty()) << bad.views[3].image_error;
  ASSERT_TRUE(cv::imwrite(JoinPaths(dir, "images", "d.png"), cv::Mat(24, 32, CV_8U, 128.0)));
  const std::string resized_report = ComputeWorkspaceInfo(dir, "", SourceViewOptions()).Report();
  for (const char* part : {"image UNUSABLE", "Unusable image: Image ", "d.png is 32 x 24"}) {
    EXPECT_NE(resized_report.find(part), std::string::npos) << part << "\n" << resized_report;
  }
}

TEST(WorkspaceInfo, SharedGantrySetHasEightTGroups) {
  const std::string dir = JoinPaths(HAIRMVS_SHARED_DATA_DIR, "synth_straight_gantry", "dense");
  if (!ExistsDir(dir)) GTEST_SKIP() << "shared data set not found: " << dir;
  const SourceViewOptions source_options;
  const WorkspaceInfo info = ComputeWorkspaceInfo(dir, "", source_options);
  // The rig: 8 groups of 4 views in a T (data README); every centre view's T is recognised.
  ASSERT_EQ(info.views.size(), 32u);
  EXPECT_EQ(info.num_t_groups, 8);
  for (const SourceViewSelection& s : info.selections) {
    const bool centre = s.reference.find("_c.png") != std::string::npos;
    EXPECT_EQ(s.gantry_t_group, centre) << s.reference << ": " << s.reason;
    EXPECT_GE(s.sources.size(), 3u) << s.reference;
    EXPECT_LE(s.sources.size(), static_cast<size_t>(source_options.max_num_source_views));
  }
  for (const WorkspaceInfoViewRow& v : info.views) {
    EXPECT_FALSE(v.mask_path.empty()) << v.name;
    EXPECT_GT(v.depth_range.min_m, 0) << v.name;
  }
}

}  // namespace
}  // namespace hairmvs
