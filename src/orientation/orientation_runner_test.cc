// RunOrientationFields on a small workspace written to a temporary folder.

#include <gtest/gtest.h>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdlib>
#include <string>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/reconstruction.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/orientation_fields.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/opencl/opencl_context.h"
#include "src/orientation/orientation_field.h"

namespace hairmvs {
namespace {

constexpr int kWidth = 80, kHeight = 60;

// A workspace with two images of bright diagonal lines and a mask excluding the left 20
// columns of b.png.
std::string MakeWorkspace() {
  char pattern[] = "/tmp/hairmvs_orientation_XXXXXX";
  const char* dir = mkdtemp(pattern);
  CHECK(dir != nullptr);
  const std::string root = dir;
  Reconstruction model;
  Camera camera;
  camera.camera_id = 1;
  camera.model_id = 1;  // PINHOLE
  camera.width = kWidth;
  camera.height = kHeight;
  camera.params = {100, 100, kWidth / 2.0, kHeight / 2.0};
  model.cameras[1] = camera;
  const char* names[] = {"a.png", "b.png"};
  for (uint32_t id = 1; id <= 2; ++id) {
    Image image;
    image.image_id = id;
    image.camera_id = 1;
    image.name = names[id - 1];
    image.cam_from_world_translation = Eigen::Vector3d(0.1 * id, 0, 0);
    model.images[id] = image;
    cv::Mat pixels(kHeight, kWidth, CV_8UC1);
    for (int r = 0; r < kHeight; ++r) {
      for (int c = 0; c < kWidth; ++c) {
        const double d = std::fmod(r + 0.5 * id * c + 100.0, 6.0) - 3.0;
        pixels.at<uint8_t>(r, c) = static_cast<uint8_t>(50 + 150 * std::exp(-d * d / 1.0));
      }
    }
    CreateDirs(JoinPaths(root, "images"));
    CHECK(cv::imwrite(JoinPaths(root, "images", names[id - 1]), pixels));
  }
  model.SortImageOrder();
  CreateDirs(JoinPaths(root, "sparse"));
  WriteReconstruction(model, JoinPaths(root, "sparse"), ModelFormat::kBinary);
  cv::Mat mask(kHeight, kWidth, CV_8UC1, cv::Scalar(255));
  mask.colRange(0, 20).setTo(0);
  CreateDirs(JoinPaths(root, "masks"));
  CHECK(cv::imwrite(JoinPaths(root, "masks", "b.png.png"), mask));
  return root;
}

TEST(RunOrientationFields, WritesEveryLevelOfEveryImage) {
  const std::string root = MakeWorkspace();
  OrientationFieldOptions options;
  OrientationFieldsRunOptions run_options;
  run_options.write_png = true;
  StageTimings timings;
  const OrientationFieldsResult result = RunOrientationFields(root, options, run_options, &timings);
  EXPECT_EQ(result.num_images, 2);
  EXPECT_EQ(result.num_files_written, 12);
  EXPECT_GT(timings.Get("filter kernel"), 0);
  const Workspace workspace = Workspace::Read(root);
  OrientationFieldComputer computer(OpenCLContext::Create(), options);
  for (const std::string name : {"a.png", "b.png"}) {
    const FloatMap gray = ReadImageGray(workspace.ImagePath(name));
    const std::string mask_path = workspace.MaskPath(name);
    const FloatMap mask =
        mask_path.empty() ? FloatMap() : ReadMask(mask_path, gray.Width(), gray.Height());
    const auto expected = computer.Compute(gray, mask);
    const int widths[] = {80, 40, 20}, heights[] = {60, 30, 15};
    for (int l = 0; l < 3; ++l) {
      const std::string path = workspace.OrientationMapPath(name, l);
      const FloatMap map = ReadMat(path);
      ASSERT_EQ(map.Width(), widths[l]);
      ASSERT_EQ(map.Height(), heights[l]);
      ASSERT_EQ(map.Channels(), 2);
      EXPECT_EQ(map.Data(), expected[l].Data()) << path;
      EXPECT_TRUE(ExistsFile(path.substr(0, path.size() - 4) + ".png"));
    }
  }
  // The mask of b.png excludes its left 20 columns at level 0 (10 at level 1).
  const FloatMap b0 = ReadMat(workspace.OrientationMapPath("b.png", 0));
  const FloatMap a0 = ReadMat(workspace.OrientationMapPath("a.png", 0));
  int a_nonzero = 0;
  for (int r = 0; r < kHeight; ++r) {
    for (int c = 0; c < 20; ++c) {
      ASSERT_EQ(b0.At(r, c, 0), 0.0f);
      ASSERT_EQ(b0.At(r, c, 1), 0.0f);
      a_nonzero += a0.At(r, c, 0) != 0 || a0.At(r, c, 1) != 0;
    }
  }
  EXPECT_GT(a_nonzero, 200);
  std::system(("rm -rf " + root).c_str());
}

TEST(RunOrientationFields, ImageSubsetAndErrors) {
  const std::string root = MakeWorkspace();
  OrientationFieldsRunOptions run_options;
  run_options.image_names = {"b.png"};
  const auto result = RunOrientationFields(root, OrientationFieldOptions(), run_options, nullptr);
  EXPECT_EQ(result.num_images, 1);
  const Workspace workspace = Workspace::Read(root);
  EXPECT_TRUE(ExistsFile(workspace.OrientationMapPath("b.png", 2)));
  EXPECT_FALSE(ExistsFile(workspace.OrientationMapPath("a.png", 0)));

  run_options.image_names = {"missing.png"};
  EXPECT_THROW(RunOrientationFields(root, OrientationFieldOptions(), run_options, nullptr), Error);
  run_options.image_names = {};
  run_options.opencl_device = "no-such-device";
  try {
    RunOrientationFields(root, OrientationFieldOptions(), run_options, nullptr);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--OpenCL.device 'no-such-device'"), std::string::npos)
        << e.what();
  }
  OrientationFieldOptions bad;
  bad.num_levels = 0;
  run_options.opencl_device = "";
  EXPECT_THROW(RunOrientationFields(root, bad, run_options, nullptr), Error);
  std::system(("rm -rf " + root).c_str());
}

}  // namespace
}  // namespace hairmvs
