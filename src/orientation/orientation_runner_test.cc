// RunOrientationFields on a small workspace written to a temporary folder, and the reuse of the
// fields it caches (orientation_maps.h).

#include <gtest/gtest.h>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/reconstruction.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/orientation_fields.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/opencl/opencl_context.h"
#include "src/orientation/orientation_field.h"
#include "src/orientation/orientation_maps.h"

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
  EXPECT_EQ(result.num_files_written, 14);  // 3 levels, 3 pictures and the provenance each
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
  // A device that does not exist is named, before any output folder is made.
  run_options.opencl_device = "no-such-device";
  try {
    RunOrientationFields(root, OrientationFieldOptions(), run_options, nullptr);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--OpenCL.device 'no-such-device'"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(ExistsDir(ParentPath(Workspace::Read(root).OrientationMapPath("b.png", 0))));
  run_options.opencl_device = "";
  run_options.image_names = {"b.png"};
  const auto result = RunOrientationFields(root, OrientationFieldOptions(), run_options, nullptr);
  EXPECT_EQ(result.num_images, 1);
  const Workspace workspace = Workspace::Read(root);
  EXPECT_TRUE(ExistsFile(workspace.OrientationMapPath("b.png", 2)));
  EXPECT_FALSE(ExistsFile(workspace.OrientationMapPath("a.png", 0)));

  run_options.image_names = {"missing.png"};
  EXPECT_THROW(RunOrientationFields(root, OrientationFieldOptions(), run_options, nullptr), Error);
  run_options.image_names = {};
  OrientationFieldOptions bad;
  bad.num_levels = 0;
  EXPECT_THROW(RunOrientationFields(root, bad, run_options, nullptr), Error);
  std::system(("rm -rf " + root).c_str());
}

// With max_image_size the fields are those the stereo reads at the same size (the image
// area-resized): its cache check holds for them, and a second run keeps them.
TEST(RunOrientationFields, AtTheStereosMaxImageSize) {
  const std::string root = MakeWorkspace();
  OrientationFieldsRunOptions run_options;
  run_options.max_image_size = kWidth / 2;
  const OrientationFieldOptions options;
  EXPECT_EQ(RunOrientationFields(root, options, run_options, nullptr).num_images, 2);
  const Workspace workspace = Workspace::Read(root);
  const StereoCamera camera = workspace.ViewCamera("b.png").AtMaxImageSize(kWidth / 2);
  ASSERT_EQ(camera.width, kWidth / 2);
  const FloatMap level0 = ReadMat(workspace.OrientationMapPath("b.png", 0));
  EXPECT_EQ(level0.Width(), kWidth / 2);
  EXPECT_EQ(level0.Height(), kHeight / 2);
  const std::string provenance =
      OrientationFieldsProvenance(workspace, "b.png", camera.width, camera.height, options);
  std::string why_not;
  EXPECT_TRUE(ReadCachedOrientationFields(workspace, "b.png", provenance, camera,
                                          options.num_levels, &why_not))
      << why_not;
  EXPECT_EQ(RunOrientationFields(root, options, run_options, nullptr).num_up_to_date, 2);
  // At full size they are computed again.
  run_options.max_image_size = -1;
  EXPECT_EQ(RunOrientationFields(root, options, run_options, nullptr).num_images, 2);
  EXPECT_EQ(ReadMat(workspace.OrientationMapPath("b.png", 0)).Width(), kWidth);
  run_options.max_image_size = 0;
  EXPECT_THROW(RunOrientationFields(root, options, run_options, nullptr), Error);
  std::system(("rm -rf " + root).c_str());
}

// The cached fields are reused while the image, the mask, the size and the filter options they
// were computed from still hold, and only then; each miss says why.
TEST(OrientationMaps, ReusedOnlyWhileTheirProvenanceHolds) {
  const std::string root = MakeWorkspace();
  OrientationFieldsRunOptions run_options;
  EXPECT_EQ(RunOrientationFields(root, OrientationFieldOptions(), run_options, nullptr).num_images,
            2);
  // orientation_fields itself keeps what is up to date, computes what is not, and everything
  // with skip_up_to_date 0.
  OrientationFieldsResult again =
      RunOrientationFields(root, OrientationFieldOptions(), run_options, nullptr);
  EXPECT_EQ(again.num_images, 0);
  EXPECT_EQ(again.num_up_to_date, 2);
  run_options.write_png = true;  // the pictures are missing
  EXPECT_EQ(RunOrientationFields(root, OrientationFieldOptions(), run_options, nullptr).num_images,
            2);
  OrientationFieldOptions narrow;
  narrow.sigma_along_px = 3;
  EXPECT_EQ(RunOrientationFields(root, narrow, run_options, nullptr).num_images, 2);
  // Fields computed again without pictures take the old pictures away, so that a later
  // --write_png 1 does not find them up to date beside fields they do not show.
  run_options.write_png = false;
  EXPECT_EQ(RunOrientationFields(root, OrientationFieldOptions(), run_options, nullptr).num_images,
            2);
  EXPECT_FALSE(ExistsFile(OrientationPicturePath(Workspace::Read(root), "a.png", 0)));
  run_options.write_png = true;
  EXPECT_EQ(RunOrientationFields(root, OrientationFieldOptions(), run_options, nullptr).num_images,
            2);
  EXPECT_TRUE(ExistsFile(OrientationPicturePath(Workspace::Read(root), "a.png", 2)));
  run_options.skip_up_to_date = false;
  again = RunOrientationFields(root, OrientationFieldOptions(), run_options, nullptr);
  EXPECT_EQ(again.num_images, 2);
  EXPECT_EQ(again.num_up_to_date, 0);
  const Workspace workspace = Workspace::Read(root);
  // Levels of 80 x 60, 40 x 30 and 20 x 15.
  const StereoCamera camera = workspace.ViewCamera("a.png");
  auto read = [&](const std::string& name, const OrientationFieldOptions& options,
                  std::string* why_not, int width = kWidth, int height = kHeight) {
    return ReadCachedOrientationFields(
        workspace, name, OrientationFieldsProvenance(workspace, name, width, height, options),
        camera, 3, why_not);
  };
  std::string why_not;
  OrientationFieldOptions options;
  auto cached = read("a.png", options, &why_not);
  ASSERT_TRUE(cached.has_value()) << why_not;
  EXPECT_EQ(why_not, "");
  ASSERT_EQ(cached->size(), 3u);
  for (int l = 0; l < 3; ++l) {
    EXPECT_EQ((*cached)[l].Data(), ReadMat(workspace.OrientationMapPath("a.png", l)).Data());
  }
  // Level k does not depend on how many levels are computed.
  options.num_levels = 1;
  EXPECT_TRUE(read("a.png", options, &why_not).has_value()) << why_not;
  // Nor, with dark strands, on the bright-strand test's ratio, which is not read then.
  options = OrientationFieldOptions();
  options.min_positive_response_ratio = 0.01;
  EXPECT_TRUE(read("a.png", options, &why_not).has_value()) << why_not;
  options.dark_strands = false;
  EXPECT_NE(OrientationFieldsProvenance(workspace, "a.png", kWidth, kHeight, options),
            OrientationFieldsProvenance(workspace, "a.png", kWidth, kHeight, [] {
              OrientationFieldOptions bright;
              bright.dark_strands = false;
              return bright;
            }()));
  // Values that differ past the 6th digit are other values (a stream's default precision made
  // 0.3333333 and 0.333333 one line, and stale fields were reused).
  OrientationFieldOptions third, nearly_third;
  third.confidence_gamma = 0.3333333;
  nearly_third.confidence_gamma = 0.333333;
  EXPECT_NE(OrientationFieldsProvenance(workspace, "a.png", kWidth, kHeight, third),
            OrientationFieldsProvenance(workspace, "a.png", kWidth, kHeight, nearly_third));
  options = OrientationFieldOptions();

  // Another filter option, another size.
  options.dark_strands = false;
  EXPECT_FALSE(read("a.png", options, &why_not).has_value());
  EXPECT_NE(why_not.find("a.png.provenance.txt says `OrientationField.dark_strands = 1`, now "
                         "`OrientationField.dark_strands = 0`"),
            std::string::npos)
      << why_not;
  EXPECT_FALSE(read("a.png", OrientationFieldOptions(), &why_not, 40, 30).has_value());
  EXPECT_NE(why_not.find("says `size 80 x 60`, now `size 40 x 30`"), std::string::npos)
      << why_not;

  // A replaced mask, a replaced image.
  cv::Mat mask(kHeight, kWidth, CV_8UC1, cv::Scalar(255));
  mask.colRange(0, 30).setTo(0);
  CHECK(cv::imwrite(workspace.MaskPath("b.png"), mask));
  EXPECT_FALSE(read("b.png", OrientationFieldOptions(), &why_not).has_value());
  EXPECT_NE(why_not.find("says `mask "), std::string::npos) << why_not;
  CHECK(cv::imwrite(workspace.ImagePath("a.png"), cv::Mat(kHeight, kWidth, CV_8UC1,
                                                          cv::Scalar(7))));
  EXPECT_FALSE(read("a.png", OrientationFieldOptions(), &why_not).has_value());
  EXPECT_NE(why_not.find("says `image "), std::string::npos) << why_not;

  // Writing replaces the provenance with the new one; a truncated or missing level is a miss.
  const std::string provenance =
      OrientationFieldsProvenance(workspace, "a.png", kWidth, kHeight, OrientationFieldOptions());
  OrientationFieldComputer computer(OpenCLContext::Create(), OrientationFieldOptions());
  WriteOrientationFields(workspace, "a.png", provenance,
                         computer.Compute(ReadImageGray(workspace.ImagePath("a.png")), FloatMap()));
  const std::string provenance_path = workspace.OrientationMapProvenancePath("a.png");
  const std::string written = ReadTextFile(provenance_path);
  EXPECT_EQ(written.rfind(provenance, 0), 0u) << written;
  EXPECT_NE(written.find("\nlevel 2 "), std::string::npos) << written;
  EXPECT_TRUE(read("a.png", OrientationFieldOptions(), &why_not).has_value()) << why_not;
  // Written again with the same bytes (as the stereo does when it needs one level more), a
  // level keeps its picture; a level whose bytes change loses it.
  const std::string picture0 = OrientationPicturePath(workspace, "a.png", 0);
  WriteFileAtomically(picture0, [](std::ostream& out) { out << "a picture of level 0"; });
  const std::vector<FloatMap> levels =
      computer.Compute(ReadImageGray(workspace.ImagePath("a.png")), FloatMap());
  WriteOrientationFields(workspace, "a.png", provenance, levels);
  EXPECT_TRUE(ExistsFile(picture0));
  std::vector<FloatMap> changed = levels;
  changed[0].Data()[0] += 1.0f;
  WriteOrientationFields(workspace, "a.png", provenance, changed);
  EXPECT_FALSE(ExistsFile(picture0));
  WriteOrientationFields(workspace, "a.png", provenance, levels);
  EXPECT_EQ(ReadTextFile(provenance_path), written);
  // Fewer levels than before: the replaced fields' level beyond them goes too, unlisted.
  std::vector<FloatMap> four = levels;
  four.push_back(levels.back());
  WriteOrientationFields(workspace, "a.png", provenance, four);
  EXPECT_TRUE(ExistsFile(workspace.OrientationMapPath("a.png", 3)));
  WriteOrientationFields(workspace, "a.png", provenance, levels);
  EXPECT_FALSE(ExistsFile(workspace.OrientationMapPath("a.png", 3)));
  EXPECT_EQ(ReadTextFile(provenance_path), written);
  // A level that another run replaced after this provenance was written (the same size: the
  // payload tells) is not taken for this provenance's, nor is a provenance of an older hairmvs
  // that records no levels.
  const std::string level0 = workspace.OrientationMapPath("a.png", 0);
  const std::string level0_bytes = ReadTextFile(level0);
  OrientationFieldOptions other_filter;
  other_filter.sigma_along_px = 3;
  WriteMat(level0, OrientationFieldComputer(OpenCLContext::Create(), other_filter)
                       .Compute(ReadImageGray(workspace.ImagePath("a.png")), FloatMap())[0]);
  ASSERT_NE(ReadTextFile(level0), level0_bytes);
  EXPECT_FALSE(read("a.png", OrientationFieldOptions(), &why_not).has_value());
  EXPECT_NE(why_not.find("changed after their provenance was written (" + level0 + " is "),
            std::string::npos)
      << why_not;
  // orientation_fields computes such a level again: it checks the bytes as the stereo does.
  OrientationFieldsRunOptions a_only;
  a_only.image_names = {"a.png"};
  EXPECT_EQ(RunOrientationFields(root, OrientationFieldOptions(), a_only, nullptr).num_images, 1);
  EXPECT_EQ(ReadTextFile(level0), level0_bytes);
  EXPECT_EQ(RunOrientationFields(root, OrientationFieldOptions(), a_only, nullptr).num_up_to_date,
            1);
  WriteFileAtomically(level0, [&](std::ostream& out) { out << level0_bytes; });
  EXPECT_TRUE(read("a.png", OrientationFieldOptions(), &why_not).has_value()) << why_not;
  WriteFileAtomically(provenance_path, [&](std::ostream& out) { out << provenance; }, false);
  EXPECT_FALSE(read("a.png", OrientationFieldOptions(), &why_not).has_value());
  EXPECT_NE(why_not.find("records no level 0 (written by an older hairmvs)"), std::string::npos)
      << why_not;
  WriteFileAtomically(provenance_path, [&](std::ostream& out) { out << written; }, false);
  std::filesystem::resize_file(workspace.OrientationMapPath("a.png", 1), 100);
  EXPECT_FALSE(read("a.png", OrientationFieldOptions(), &why_not).has_value());
  EXPECT_NE(why_not.find("cannot be read"), std::string::npos) << why_not;
  std::filesystem::remove(workspace.OrientationMapPath("a.png", 2));
  std::filesystem::remove(workspace.OrientationMapPath("a.png", 1));
  EXPECT_FALSE(read("a.png", OrientationFieldOptions(), &why_not).has_value());
  EXPECT_NE(why_not.find("stop before level 1"), std::string::npos) << why_not;

  // Levels without a provenance (an older hairmvs) are a miss that says so; nothing cached at
  // all is a miss without a word.
  std::filesystem::remove(workspace.OrientationMapProvenancePath("a.png"));
  EXPECT_FALSE(read("a.png", OrientationFieldOptions(), &why_not).has_value());
  EXPECT_NE(why_not.find("have no " + workspace.OrientationMapProvenancePath("a.png")),
            std::string::npos)
      << why_not;
  std::filesystem::remove(workspace.OrientationMapPath("a.png", 0));
  EXPECT_FALSE(read("a.png", OrientationFieldOptions(), &why_not).has_value());
  EXPECT_EQ(why_not, "");
  std::system(("rm -rf " + root).c_str());
}

}  // namespace
}  // namespace hairmvs
