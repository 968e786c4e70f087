// RunOrientationStereo on a small synthetic workspace written to disk: four 96 x 72 PINHOLE
// views of a plane covered in bright strands, orientation fields computed by the real filter
// bank. Checks that --image_names writes only its views and that the depth is recovered.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/reconstruction.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/orientation_stereo.h"
#include "src/core/file_util.h"
#include "src/stereo/stereo_test_util.h"

namespace hairmvs {
namespace {

using namespace testing_util;

// Writes the workspace; returns the true depth of view 0.
FloatMap WriteWorkspace(const std::string& path) {
  Surface plane;
  plane.point = {0, 0, 1};
  plane.normal = Eigen::Vector3d(std::sin(0.3), 0, -std::cos(0.3));
  const auto strands = MakeStrands(plane, 900, 0.6, 0.25, 5);
  const Eigen::Vector3d target(0, 0, 1);
  const std::vector<StereoCamera> cameras = {
      LookAtCamera({0, 0, 0}, target, 100, 96, 72), LookAtCamera({0.3, 0, 0}, target, 100, 96, 72),
      LookAtCamera({-0.3, 0, 0}, target, 100, 96, 72),
      LookAtCamera({0, -0.3, 0}, target, 100, 96, 72)};
  Reconstruction model;
  Camera camera;
  camera.camera_id = 1;
  camera.model_id = 1;  // PINHOLE
  camera.width = 96;
  camera.height = 72;
  camera.params = {100, 100, 48, 36};
  model.cameras[1] = camera;
  FloatMap true_depth;
  CreateDirs(JoinPaths(path, "images"));
  for (size_t i = 0; i < cameras.size(); ++i) {
    const RenderedView view = RenderView(cameras[i], plane, strands);
    if (i == 0) true_depth = view.depth;
    Image image;
    image.image_id = static_cast<uint32_t>(i + 1);
    image.camera_id = 1;
    image.name = "v" + std::to_string(i) + ".png";
    image.cam_from_world_rotation = Eigen::Quaterniond(cameras[i].R);
    image.cam_from_world_translation = cameras[i].t;
    model.images[image.image_id] = image;
    cv::Mat gray(72, 96, CV_8U);
    for (int row = 0; row < 72; ++row) {
      for (int col = 0; col < 96; ++col) {
        gray.at<uint8_t>(row, col) =
            static_cast<uint8_t>(std::lround(20 + 235 * view.gray.At(row, col)));
      }
    }
    cv::imwrite(JoinPaths(path, "images", image.name), gray);
  }
  model.SortImageOrder();
  CreateDirs(JoinPaths(path, "sparse"));
  WriteReconstruction(model, JoinPaths(path, "sparse"), ModelFormat::kText);
  CreateDirs(JoinPaths(path, "stereo"));
  std::ofstream cfg(JoinPaths(path, "stereo", "patch-match.cfg"));
  for (int i = 0; i < 4; ++i) {
    cfg << "v" << i << ".png\n";
    bool first = true;
    for (int j = 0; j < 4; ++j) {
      if (j == i) continue;
      cfg << (first ? "" : ", ") << "v" << j << ".png";
      first = false;
    }
    cfg << "\n";
  }
  return true_depth;
}

TEST(OrientationStereoWorkspace, ImageNamesWritesOnlyItsViewsAndRecoversThePlane) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "hairmvs_stereo_workspace_test").string();
  std::filesystem::remove_all(path);
  const FloatMap true_depth = WriteWorkspace(path);
  OrientationStereoOptions options;
  options.depth_min = 0.7;
  options.depth_max = 1.5;
  options.coarse_level = 1;
  options.write_png = true;
  StageTimings timings;
  const OrientationStereoResult result =
      RunOrientationStereo(path, {"v0.png"}, options, &timings);
  EXPECT_EQ(result.num_views, 1);
  const Workspace workspace = Workspace::Read(path);
  ASSERT_TRUE(ExistsFile(workspace.DepthMapPath("v0.png")));
  EXPECT_TRUE(ExistsFile(workspace.NormalMapPath("v0.png")));
  EXPECT_TRUE(ExistsFile(workspace.ConfidenceMapPath("v0.png")));
  for (const char* other : {"v1.png", "v2.png", "v3.png"}) {
    EXPECT_FALSE(ExistsFile(workspace.DepthMapPath(other))) << other;
  }
  const FloatMap depth = ReadMat(workspace.DepthMapPath("v0.png"));
  ASSERT_EQ(depth.Width(), 96);
  ASSERT_EQ(depth.Height(), 72);
  std::vector<double> errors;
  for (size_t p = 0; p < depth.Data().size(); ++p) {
    if (depth.Data()[p] > 0 && true_depth.Data()[p] > 0) {
      errors.push_back(std::abs(depth.Data()[p] - true_depth.Data()[p]));
    }
  }
  ASSERT_GT(errors.size(), depth.Data().size() / 2);
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  const double median = errors[errors.size() / 2];
  std::printf("workspace plane: median |error| %.4f m over %zu pixels\n", median, errors.size());
  // About one pixel of disparity over the 0.3 m baselines at 1 m is 30 mm.
  EXPECT_LT(median, 0.02);
  // The orientation fields were cached for reuse.
  EXPECT_TRUE(ExistsFile(workspace.OrientationMapPath("v1.png", 0)));
  std::filesystem::remove_all(path);
}

}  // namespace
}  // namespace hairmvs
