// Round trips through the real `colmap` binary: what COLMAP writes we read, what we write
// COLMAP reads (colmap-formats.md sections 4, 5 and 9).

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <csignal>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "colmap_ext/image_undistorter.h"
#include "colmap_ext/mat_io.h"
#include "colmap_ext/ply.h"
#include "colmap_ext/reconstruction.h"
#include "colmap_ext/source_views.h"
#include "colmap_ext/test_util.h"
#include "colmap_ext/workspace.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace hairmvs {
namespace {

using testing_util::ErrorOf;
using testing_util::ExpectModelsEqual;
using testing_util::MakePlaneModel;
using testing_util::MakeTestDir;

std::string Format(double value) {
  std::ostringstream ss;
  ss << std::setprecision(3) << value;
  return ss.str();
}

std::string ColmapExecutable() {
  const char* env = std::getenv("HAIRMVS_COLMAP_EXECUTABLE");
  return env != nullptr && *env ? env : HAIRMVS_COLMAP_EXECUTABLE;
}

// Runs `colmap <args>` offscreen; returns the exit code; the output goes to `log_path`.
int RunColmap(const std::string& args, const std::string& log_path) {
  const std::string command = "QT_QPA_PLATFORM=offscreen '" + ColmapExecutable() + "' " + args +
                              " > '" + log_path + "' 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

#define REQUIRE_COLMAP()                                                        \
  do {                                                                          \
    if (!ExistsFile(ColmapExecutable())) {                                      \
      GTEST_SKIP() << "colmap executable not found: " << ColmapExecutable();    \
    }                                                                           \
  } while (0)

#define EXPECT_COLMAP_OK(args, dir)                                            \
  do {                                                                         \
    const std::string log_ = JoinPaths(dir, "colmap.log");                     \
    const int rc_ = RunColmap(args, log_);                                     \
    ASSERT_EQ(rc_, 0) << "colmap " << args << "\n" << ReadTextFile(log_);      \
  } while (0)

Reconstruction ModelWithSomeCameraModels() {
  Reconstruction model = MakePlaneModel();
  // The models 3.8 knows (ids 0-10) all load; keep the images on their PINHOLE cameras.
  for (int id = 0; id <= 10; ++id) {
    Camera camera;
    camera.camera_id = 50 + id;
    camera.model_id = id;
    camera.width = 640;
    camera.height = 480;
    const int n = CameraModelById(id).num_params;
    for (int k = 0; k < n; ++k) camera.params.push_back(k < 2 ? 500.0 + k / 3.0 : 1e-3 * k);
    if (id == 7) camera.params[4] = 0.7;  // FOV omega
    model.cameras[camera.camera_id] = camera;
  }
  // Poses with full-precision values.
  for (auto& [id, image] : model.images) {
    image.cam_from_world_rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * id, Eigen::Vector3d(1, 2, 3).normalized()));
    image.cam_from_world_translation += Eigen::Vector3d(1.0 / 3, -2.0 / 7, 0.1);
  }
  return model;
}

TEST(ColmapInterop, ModelsWrittenByColmapReadBackIdentically) {
  REQUIRE_COLMAP();
  const std::string dir = MakeTestDir("interop_models");
  const Reconstruction model = ModelWithSomeCameraModels();
  for (const ModelFormat ours : {ModelFormat::kBinary, ModelFormat::kText}) {
    const std::string tag = ours == ModelFormat::kBinary ? "bin" : "txt";
    const std::string input = JoinPaths(dir, "ours_" + tag);
    WriteReconstruction(model, input, ours);
    for (const std::string type : {"BIN", "TXT"}) {
      const std::string output = JoinPaths(dir, "colmap_from_" + tag + "_" + type);
      CreateDirs(output);
      // COLMAP reads our model (bin or txt) and writes it back in its own format.
      EXPECT_COLMAP_OK("model_converter --input_path " + input + " --output_path " + output +
                           " --output_type " + type,
                       dir);
      const Reconstruction read = ReadReconstruction(output);
      // Exact but for the quaternions, which COLMAP 3.8 normalises again when reading and
      // writing (a change of one ulp).
      ExpectModelsEqual(model, read, 1e-15);
      // COLMAP 3.8 writes images in hash-map order: image_order is that file order.
      EXPECT_EQ(read.image_order.size(), model.images.size());
    }
  }
  // COLMAP's BIN and TXT of the same model read back identically.
  ExpectModelsEqual(ReadReconstruction(JoinPaths(dir, "colmap_from_txt_BIN")),
                    ReadReconstruction(JoinPaths(dir, "colmap_from_txt_TXT")), 0.0);
}

TEST(ColmapInterop, ColmapRejectsWhatWeReject) {
  REQUIRE_COLMAP();
  // A PINHOLE camera with 3 parameters: COLMAP aborts, we throw naming the file and line.
  const std::string dir = MakeTestDir("interop_reject");
  const std::string model_dir = JoinPaths(dir, "model");
  WriteReconstruction(MakePlaneModel(), model_dir, ModelFormat::kText);
  WriteFileAtomically(JoinPaths(model_dir, "cameras.txt"),
                      [](std::ostream& out) { out << "1 PINHOLE 64 48 50 50 32\n"; });
  CreateDirs(JoinPaths(dir, "out"));
  EXPECT_NE(RunColmap("model_converter --input_path " + model_dir + " --output_path " +
                          JoinPaths(dir, "out") + " --output_type BIN",
                      JoinPaths(dir, "colmap.log")),
            0);
  EXPECT_THROW(ReadReconstruction(model_dir), Error);
}

// A tilted plane z = 5 + 0.2 x seen by PINHOLE views with identity rotation.
constexpr double kPlaneZ = 5.0;
constexpr double kPlaneSlope = 0.2;

double PlaneDistance(const Eigen::Vector3d& x) {
  return std::abs(x.z() - kPlaneZ - kPlaneSlope * x.x()) / std::sqrt(1 + kPlaneSlope * kPlaneSlope);
}

// Depth and normal maps of the plane in COLMAP's MVS pixel convention (pixel (c, r) is
// back-projected through image point (c, r), section 2).
void WritePlaneMaps(const Workspace& ws) {
  for (const std::string& name : ws.ImageNames()) {
    const Image& image = ws.ImageByName(name);
    const Camera& camera = ws.CameraOf(name);
    const Eigen::Matrix3d K = camera.CalibrationMatrix();
    const Eigen::Vector3d centre = image.ProjectionCenter();
    FloatMap depth(static_cast<int>(camera.width), static_cast<int>(camera.height), 1);
    FloatMap normal(depth.Width(), depth.Height(), 3);
    const Eigen::Vector3d n = Eigen::Vector3d(kPlaneSlope, 0, -1).normalized();  // faces cameras
    for (int r = 0; r < depth.Height(); ++r) {
      for (int c = 0; c < depth.Width(); ++c) {
        const double x = (c - K(0, 2)) / K(0, 0);
        // centre.z + d = kPlaneZ + slope * (centre.x + d x)
        const double d = (kPlaneZ + kPlaneSlope * centre.x() - centre.z()) / (1 - kPlaneSlope * x);
        depth.At(r, c) = static_cast<float>(d);
        for (int k = 0; k < 3; ++k) normal.At(r, c, k) = static_cast<float>(n[k]);
      }
    }
    WriteMat(ws.DepthMapPath(name), depth);
    WriteMat(ws.NormalMapPath(name), normal);
  }
  WriteFusionConfig(JoinPaths(ws.StereoPath(), "fusion.cfg"), ws.ImageNames());
}

TEST(ColmapInterop, StereoFusionFusesOurDepthAndNormalMaps) {
  REQUIRE_COLMAP();
  const std::string dir = MakeTestDir("interop_fusion");
  testing_util::PlaneModelOptions options;
  options.centres = {{0, 0, 0}, {0.5, 0, 0}, {0, 0.5, 0}};
  testing_util::WriteTestWorkspace(dir, MakePlaneModel(options));
  const Workspace ws = Workspace::Read(dir);
  WritePlaneMaps(ws);
  const std::string fused = JoinPaths(dir, "fused.ply");
  EXPECT_COLMAP_OK("stereo_fusion --workspace_path " + dir +
                       " --input_type geometric --output_path " + fused +
                       " --StereoFusion.min_num_pixels 2 --StereoFusion.num_threads 1",
                   dir);
  const std::vector<FusedPoint> points = ReadFusedPly(fused);
  // Each view sees 64 x 48 pixels; the overlaps are 54 or 59 columns / 38 rows wide, so
  // COLMAP's greedy fusion yields well over 1000 points.
  ASSERT_GT(points.size(), 1000u);
  const Eigen::Vector3f plane_normal = Eigen::Vector3f(kPlaneSlope, 0, -1).normalized();
  double max_distance = 0;
  for (const FusedPoint& p : points) {
    max_distance = std::max(max_distance, PlaneDistance(p.xyz.cast<double>()));
    EXPECT_LT((p.normal - plane_normal).norm(), 1e-4);
    ASSERT_GE(p.visible_image_idxs.size(), 2u);
    for (uint32_t idx : p.visible_image_idxs) EXPECT_LT(idx, 3u);
  }
  // Each fused point is the per-coordinate median of back-projected pixels that all lie on
  // the plane (within float32 rounding, about 5e-7 m at 5 m); a median of points on a tilted
  // plane need not lie on it, but the fused pixels nearly coincide: 1e-4 m is 1/1000 of the
  // pixel footprint (0.1 m at 5 m, f = 50 px).
  EXPECT_LT(max_distance, 1e-4) << "max distance to the true plane (m)";
  RecordProperty("max_plane_distance_m", Format(max_distance));
  RecordProperty("num_fused_points", std::to_string(points.size()));

  // Writing COLMAP's points back with WriteFusedPly gives byte-identical files.
  const std::string ours = JoinPaths(dir, "ours.ply");
  WriteFusedPly(ours, points);
  EXPECT_EQ(ReadTextFile(ours), ReadTextFile(fused));
  EXPECT_EQ(ReadTextFile(ours + ".vis"), ReadTextFile(fused + ".vis"));
}

// A --max_image_size that image_undistorter cannot take (colmap aborts on 0) is refused before
// anything is read or run (so this needs no colmap).
TEST(ColmapInterop, UndistortMasksRefusesABadMaxImageSize) {
  for (const int bad : {0, -7}) {
    const std::string error = ErrorOf([&] {
      UndistortMasks("/nonexistent/colmap", "/no/masks", "/no/sparse", "/no/ws", bad);
    });
    EXPECT_NE(error.find("--max_image_size " + std::to_string(bad) + " must be > 0 or -1 (none)"),
              std::string::npos)
        << error;
  }
}

// Masks drawn on distorted photos are undistorted as the photos are: the written mask matches
// the undistorted photo's own content pixel for pixel (but its rim), where the photo's mask
// merely resized to the new size does not. A photo without a mask gets none; a mask of another
// aspect ratio is named. A workspace undistorted with --max_image_size needs it given too; a
// failure writes no mask, and masks the workspace has are replaced only when asked.
TEST(ColmapInterop, UndistortMasksAsThePhotos) {
  REQUIRE_COLMAP();
  const std::string dir = MakeTestDir("interop_undistort_masks");
  const int width = 320, height = 240;
  // Bright discs on a dark ground, so that a photo's content is its own mask.
  cv::Mat photo(height, width, CV_8UC3, cv::Scalar(20, 30, 40));
  for (int row = 0; row < 5; ++row) {
    for (int col = 0; col < 7; ++col) {
      cv::circle(photo, cv::Point(20 + 46 * col, 20 + 50 * row), 14, cv::Scalar(230, 220, 210),
                 cv::FILLED);
    }
  }
  // A picture's own mask: its bright pixels.
  auto content_mask = [](const cv::Mat& bgr) {
    cv::Mat mask;
    cv::cvtColor(bgr, mask, cv::COLOR_BGR2GRAY);
    cv::threshold(mask, mask, 127, 255, cv::THRESH_BINARY);
    return mask;
  };
  const cv::Mat photo_mask = content_mask(photo);
  const std::string photos = JoinPaths(dir, "photos"), masks = JoinPaths(dir, "photo_masks");
  CreateDirs(photos);
  CreateDirs(masks);
  Reconstruction model = MakePlaneModel();  // a.png, b.png, c.png
  model.images.at(1).name = "a.jpg";        // masks are <photo name>.png whatever the format
  for (auto& [id, camera] : model.cameras) {
    camera.model_id = CameraModelByName("OPENCV").id;
    camera.width = width;
    camera.height = height;
    camera.params = {200, 200, width / 2.0, height / 2.0, -0.3, 0.05, 0.001, -0.001};
  }
  for (const auto& [id, image] : model.images) {
    ASSERT_TRUE(cv::imwrite(JoinPaths(photos, image.name), photo));
  }
  ASSERT_TRUE(cv::imwrite(JoinPaths(masks, "a.jpg.png"), photo_mask));
  cv::Mat mask_with_ones;  // keep = 1, not 255: any non-zero value keeps, as in COLMAP
  photo_mask.convertTo(mask_with_ones, CV_8U, 1.0 / 255);
  ASSERT_TRUE(cv::imwrite(JoinPaths(masks, "b.png.png"), mask_with_ones));
  const std::string sparse = JoinPaths(dir, "sparse");
  CreateDirs(sparse);
  WriteReconstruction(model, sparse, ModelFormat::kText);

  const std::string workspace_path = JoinPaths(dir, "dense");
  RunImageUndistorter(ColmapExecutable(), photos, sparse, workspace_path);
  // A folder with no mask of any photo (masks named without the photo's extension, say).
  const std::string misnamed = JoinPaths(dir, "misnamed");
  CreateDirs(misnamed);
  ASSERT_TRUE(cv::imwrite(JoinPaths(misnamed, "a.png"), photo_mask));
  const std::string no_mask_error =
      ErrorOf([&] { UndistortMasks(ColmapExecutable(), misnamed, sparse, workspace_path); });
  EXPECT_NE(no_mask_error.find("No mask in " + misnamed + " belongs to an image"),
            std::string::npos)
      << no_mask_error;
  EXPECT_FALSE(ExistsDir(JoinPaths(workspace_path, "masks")));
  ::testing::internal::CaptureStderr();
  const MaskUndistortionResult result =
      UndistortMasks(ColmapExecutable(), masks, sparse, workspace_path);
  // The photos' masks are at the photos' sizes, a few percent off the images': no warning.
  const std::string undistort_log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(undistort_log.find("a few percent off"), std::string::npos) << undistort_log;
  EXPECT_EQ(result.num_masks, 2);
  EXPECT_EQ(result.images_without_mask, std::vector<std::string>{"c.png"});

  const Workspace ws = Workspace::Read(workspace_path);
  EXPECT_EQ(ws.ImagesWithoutMask(), std::vector<std::string>{"c.png"});
  for (const std::string name : {"a.jpg", "b.png"}) {
    const Camera& camera = ws.CameraOf(name);
    ASSERT_TRUE(camera.IsPinhole());
    ASSERT_NE(static_cast<int>(camera.width), width) << "the undistorter kept the size";
    const cv::Mat mask = cv::imread(ws.MaskPath(name), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(mask.cols, static_cast<int>(camera.width));
    ASSERT_EQ(mask.rows, static_cast<int>(camera.height));
    ASSERT_EQ(mask.type(), CV_8U);
    const cv::Mat content = content_mask(cv::imread(ws.ImagePath(name)));
    cv::Mat resized;
    cv::resize(photo_mask, resized, mask.size(), 0, 0, cv::INTER_NEAREST);
    const double n = static_cast<double>(mask.total());
    const double agree = cv::countNonZero(mask == content) / n;
    const double agree_resized = cv::countNonZero(resized == content) / n;
    EXPECT_GT(agree, 0.995) << name;
    EXPECT_LT(agree_resized, 0.95) << name << ": the distortion should matter in this test";
    RecordProperty(std::string("agreement_") + name, Format(agree));
    RecordProperty(std::string("agreement_resized_") + name, Format(agree_resized));
  }

  // A workspace the user undistorted with --max_image_size: the masks need the same option,
  // and without it the size that comes out is named.
  const std::string small_path = JoinPaths(dir, "dense_small");
  EXPECT_COLMAP_OK("image_undistorter --image_path " + photos + " --input_path " + sparse +
                       " --output_path " + small_path + " --max_image_size 200",
                   dir);
  const std::string size_error =
      ErrorOf([&] { UndistortMasks(ColmapExecutable(), masks, sparse, small_path); });
  EXPECT_NE(size_error.find("--max_image_size"), std::string::npos) << size_error;
  EXPECT_FALSE(ExistsDir(JoinPaths(small_path, "masks"))) << "a failure writes no mask";
  EXPECT_EQ(UndistortMasks(ColmapExecutable(), masks, sparse, small_path, 200).num_masks, 2);
  // Masks the workspace has are not replaced unless asked, and are named before colmap runs.
  const std::string small_mask_path = JoinPaths(small_path, "masks", "a.jpg.png");
  const std::string before = ReadTextFile(small_mask_path);
  const std::string exists_error = ErrorOf([&] {
    UndistortMasks("/nonexistent/colmap", masks, sparse, small_path, 200);
  });
  EXPECT_NE(exists_error.find("has a mask already: " + JoinPaths(small_path, "masks")),
            std::string::npos)
      << exists_error;
  EXPECT_NE(exists_error.find("--overwrite 1"), std::string::npos) << exists_error;
  EXPECT_EQ(ReadTextFile(small_mask_path), before);
  EXPECT_EQ(UndistortMasks(ColmapExecutable(), masks, sparse, small_path, 200, true).num_masks, 2);
  EXPECT_EQ(ReadTextFile(small_mask_path), before);  // the same masks again
  const Workspace small = Workspace::Read(small_path);
  const cv::Mat small_mask = cv::imread(small.MaskPath("a.jpg"), cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(small_mask.cols, 200);
  const cv::Mat small_content = content_mask(cv::imread(small.ImagePath("a.jpg")));
  EXPECT_GT(cv::countNonZero(small_mask == small_content) / double(small_mask.total()), 0.99);

  cv::Mat narrow;
  cv::resize(photo_mask, narrow, cv::Size(width, height / 2));
  ASSERT_TRUE(cv::imwrite(JoinPaths(masks, "c.png.png"), narrow));
  const std::string error =
      ErrorOf([&] { UndistortMasks(ColmapExecutable(), masks, sparse, workspace_path); });
  EXPECT_NE(error.find("c.png.png"), std::string::npos) << error;
  EXPECT_NE(error.find("aspect ratio"), std::string::npos) << error;
}

// The entries of `dir` (hidden ones too).
std::vector<std::string> FolderEntries(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// A stand-in for colmap, `dir`/`name`, that writes the start of a workspace into its
// --output_path (as colmap image_undistorter creates sparse/ first), then ends as `how` says.
std::string WriteFailingColmap(const std::string& dir, const std::string& name,
                               const std::string& how) {
  const std::string path = JoinPaths(dir, name);
  std::ofstream script(path);
  script << "#!/bin/sh\n"
         << "while [ $# -gt 0 ]; do [ \"$1\" = --output_path ] && out=$2; shift; done\n"
         << "mkdir -p \"$out/sparse\" \"$out/images\" && touch \"$out/images/a.png\"\n"
         << how << "\n";
  script.close();
  std::filesystem::permissions(path, std::filesystem::perms::owner_all);
  return path;
}

// A workspace made from photos appears only once whole: colmap failing, or not to be run,
// stopped by Ctrl-C (it and this process sent SIGINT, as a terminal sends it), passing over a
// photo, or the masks failing after it leave neither the workspace nor the hidden folder it was
// made in; a whole one is published with everything the undistorter and the step before
// publishing wrote, and removes what a run a signal ended left.
TEST(ColmapInterop, WorkspaceFromPhotosAppearsOnlyWhenWhole) {
  REQUIRE_COLMAP();
  const std::string dir = MakeTestDir("interop_publish");
  const std::string photos = JoinPaths(dir, "photos"), sparse = JoinPaths(dir, "sparse");
  CreateDirs(photos);
  CreateDirs(sparse);
  Reconstruction model = MakePlaneModel();
  WriteReconstruction(model, sparse, ModelFormat::kText);
  for (const auto& [id, image] : model.images) {
    const Camera& camera = model.cameras.at(image.camera_id);
    ASSERT_TRUE(cv::imwrite(JoinPaths(photos, image.name),
                            cv::Mat(static_cast<int>(camera.height),
                                    static_cast<int>(camera.width), CV_8UC3,
                                    cv::Scalar(40, 80, 120))));
  }
  const std::string out = JoinPaths(dir, "out");
  CreateDirs(out);
  const std::string workspace = JoinPaths(out, "dense");
  const std::vector<std::string> nothing;

  std::string error = ErrorOf([&] {
    RunImageUndistorter(WriteFailingColmap(dir, "exits", "exit 3"), photos, sparse, workspace);
  });
  EXPECT_NE(error.find("exit status 3"), std::string::npos) << error;
  EXPECT_NE(error.find("Nothing was written to " + workspace), std::string::npos) << error;
  EXPECT_EQ(FolderEntries(out), nothing);
  // A colmap that cannot be run is named before anything starts.
  EXPECT_EQ(ErrorOf([&] { RunImageUndistorter("/nonexistent/colmap", photos, sparse, workspace); }),
            "Cannot run /nonexistent/colmap: no such file; install COLMAP (apt-get install "
            "colmap), or give its path with --colmap_executable");
  EXPECT_NE(ErrorOf([&] {
              RunImageUndistorter("no_such_colmap_here", photos, sparse, workspace);
            }).find("Cannot run no_such_colmap_here: not found in PATH"),
            std::string::npos);
  EXPECT_EQ(FolderEntries(out), nothing);
  // Nor are the workspace's parent folders made, when colmap cannot run or fails.
  const std::string deeper = JoinPaths(out, "new", "deeper", "dense");
  EXPECT_THROW(RunImageUndistorter("/nonexistent/colmap", photos, sparse, deeper), Error);
  EXPECT_THROW(RunImageUndistorter(WriteFailingColmap(dir, "exits_too", "exit 3"), photos, sparse,
                                   deeper),
               Error);
  EXPECT_EQ(FolderEntries(out), nothing);

  error = ErrorOf([&] {
    RunImageUndistorter(WriteFailingColmap(dir, "interrupted", "kill -INT $PPID $$"), photos,
                        sparse, workspace);
  });
  EXPECT_NE(error.find("stopped by signal " + std::to_string(SIGINT)), std::string::npos)
      << error;
  EXPECT_EQ(FolderEntries(out), nothing);

  // The mapper's output folder given for its model (sparse/ for sparse/0): named before colmap
  // runs, where colmap would abort with a stack trace.
  const std::string mapper_output = JoinPaths(dir, "mapper_output");
  WriteReconstruction(model, JoinPaths(mapper_output, "0"), ModelFormat::kText);
  error =
      ErrorOf([&] { RunImageUndistorter(ColmapExecutable(), photos, mapper_output, workspace); });
  EXPECT_NE(error.find("found a sub-folder 0/"), std::string::npos) << error;
  EXPECT_EQ(FolderEntries(out), nothing);

  error = ErrorOf([&] {
    RunImageUndistorter(ColmapExecutable(), photos, sparse, workspace,
                        [](const std::string&) { HAIRMVS_THROW("the masks failed"); });
  });
  EXPECT_NE(error.find("the masks failed"), std::string::npos) << error;
  EXPECT_EQ(FolderEntries(out), nothing);

  // A photo that colmap cannot read is passed over with exit status 0: not published.
  const std::string photo = JoinPaths(photos, model.images.begin()->second.name);
  std::filesystem::rename(photo, photo + ".away");
  error = ErrorOf([&] { RunImageUndistorter(ColmapExecutable(), photos, sparse, workspace); });
  EXPECT_NE(error.find("colmap image_undistorter wrote no image for " + photo +
                       ", which the model " + sparse + " lists: is it missing or unreadable? "
                       "Nothing was written to " + workspace),
            std::string::npos)
      << error;
  EXPECT_EQ(FolderEntries(out), nothing);
  std::filesystem::rename(photo + ".away", photo);

  // A hidden folder that a run stopped by a signal left (its process is gone) is removed by
  // the next run; one of a process still running is not.
  const pid_t ended = fork();
  if (ended == 0) _exit(0);
  ASSERT_EQ(waitpid(ended, nullptr, 0), ended);
  const std::string left = ".dense.undistorting" + std::to_string(ended) + "_0";
  const std::string running = ".dense.undistorting1_0";  // init's
  for (const std::string& name : {left, running}) {
    CreateDirs(JoinPaths(out, name, "images"));
  }
  // Whole: the step before publishing sees the undistorted workspace, not yet published.
  RunImageUndistorter(ColmapExecutable(), photos, sparse, workspace,
                      [&](const std::string& staged) {
                        EXPECT_FALSE(ExistsDir(workspace));
                        EXPECT_TRUE(ExistsFile(JoinPaths(staged, "sparse", "cameras.bin")));
                        WriteFileAtomically(JoinPaths(staged, "masks", "a.png.png"),
                                            [](std::ostream& o) { o << "staged"; });
                      });
  EXPECT_EQ(FolderEntries(out), (std::vector<std::string>{running, "dense"}));
  const Workspace ws = Workspace::Read(workspace);
  EXPECT_EQ(ws.ImageNames().size(), model.images.size());
  for (const std::string& name : ws.ImageNames()) EXPECT_TRUE(ExistsFile(ws.ImagePath(name)));
  EXPECT_EQ(ReadTextFile(JoinPaths(workspace, "masks", "a.png.png")), "staged");
  EXPECT_TRUE(ExistsFile(JoinPaths(workspace, "stereo", "patch-match.cfg")));
  // A workspace is never made over one that has a model, nor over a folder holding an entry
  // it would replace: nothing is moved into that folder.
  error = ErrorOf([&] { RunImageUndistorter(ColmapExecutable(), photos, sparse, workspace); });
  EXPECT_NE(error.find("has a sparse/ model already"), std::string::npos) << error;
  const std::string other = JoinPaths(out, "other");
  WriteFileAtomically(JoinPaths(other, "images", "mine.txt"), [](std::ostream& o) { o << "x"; });
  error = ErrorOf([&] { RunImageUndistorter(ColmapExecutable(), photos, sparse, other); });
  EXPECT_NE(error.find("holds " + JoinPaths(other, "images") + " already; nothing was moved"),
            std::string::npos)
      << error;
  EXPECT_EQ(FolderEntries(other), std::vector<std::string>{"images"});
  EXPECT_EQ(FolderEntries(JoinPaths(other, "images")), std::vector<std::string>{"mine.txt"});
  EXPECT_EQ(FolderEntries(out), (std::vector<std::string>{running, "dense", "other"}));
  // A workspace path that is a link (to another disk, say) is staged beside the folder it
  // links to, where its entries are renamed to.
  const std::string elsewhere = JoinPaths(dir, "elsewhere");
  CreateDirs(JoinPaths(elsewhere, "dense"));
  const std::string link = JoinPaths(out, "linked");
  std::filesystem::create_directory_symlink(JoinPaths(elsewhere, "dense"), link);
  RunImageUndistorter(ColmapExecutable(), photos, sparse, link, [&](const std::string& staged) {
    EXPECT_EQ(std::filesystem::path(staged).parent_path(),
              std::filesystem::canonical(elsewhere));
  });
  EXPECT_EQ(Workspace::Read(link).ImageNames().size(), model.images.size());
  EXPECT_EQ(FolderEntries(elsewhere), std::vector<std::string>{"dense"});
  std::filesystem::remove_all(dir);
}

// Whether process `pid` exists and is not a zombie (one that no parent reaps counts as ended).
bool ProcessRuns(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return false;
  const size_t name_end = line.rfind(')');
  return name_end != std::string::npos && name_end + 2 < line.size() && line[name_end + 2] != 'Z';
}

// A SIGTERM to hairmvs alone (a scheduler's, not a terminal's Ctrl-C to the whole group) ends
// the colmap it started too, rather than leaving it writing into the hidden folder that the
// next run removes.
TEST(ColmapInterop, ColmapEndsWithTheRunThatStartedIt) {
  const std::string dir = MakeTestDir("interop_sigterm");
  const std::string photos = JoinPaths(dir, "photos"), sparse = JoinPaths(dir, "sparse");
  CreateDirs(photos);
  CreateDirs(sparse);
  WriteReconstruction(MakePlaneModel(), sparse, ModelFormat::kText);
  const std::string pid_file = JoinPaths(dir, "colmap.pid");
  const std::string colmap = WriteFailingColmap(
      dir, "lingers", "echo $$ > " + pid_file + ".tmp && mv " + pid_file + ".tmp " + pid_file +
                          " && exec sleep 120");
  const pid_t run = fork();
  ASSERT_GE(run, 0);
  if (run == 0) {
    try {
      RunImageUndistorter(colmap, photos, sparse, JoinPaths(dir, "dense"));
    } catch (...) {
    }
    _exit(0);
  }
  // Bounded waits for the processes to get where the test needs them, not timings.
  for (int i = 0; i < 600 && !ExistsFile(pid_file); ++i) usleep(100000);
  ASSERT_TRUE(ExistsFile(pid_file));
  const pid_t colmap_pid = std::stoi(ReadTextFile(pid_file));
  EXPECT_TRUE(ProcessRuns(colmap_pid));
  ASSERT_EQ(kill(run, SIGTERM), 0);
  int status = 0;
  ASSERT_EQ(waitpid(run, &status, 0), run);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  for (int i = 0; i < 200 && ProcessRuns(colmap_pid); ++i) usleep(50000);
  EXPECT_FALSE(ProcessRuns(colmap_pid)) << "colmap (" << colmap_pid << ") outlived its run";
  if (ProcessRuns(colmap_pid)) kill(colmap_pid, SIGKILL);
  std::filesystem::remove_all(dir);
}

TEST(ColmapInterop, PoissonMesherAcceptsOurFusedPly) {
  REQUIRE_COLMAP();
  const std::string dir = MakeTestDir("interop_poisson");
  // Points on a sphere of radius 1 with outward normals.
  std::vector<FusedPoint> points;
  const int n = 3000;
  for (int i = 0; i < n; ++i) {
    // Fibonacci sphere.
    const double z = 1 - 2 * (i + 0.5) / n;
    const double radius = std::sqrt(1 - z * z);
    const double phi = i * M_PI * (3 - std::sqrt(5.0));
    FusedPoint p;
    p.xyz = Eigen::Vector3f(radius * std::cos(phi), radius * std::sin(phi), z);
    p.normal = p.xyz;
    p.rgb[0] = 200;
    p.visible_image_idxs = {0};
    points.push_back(p);
  }
  const std::string ply = JoinPaths(dir, "fused.ply");
  WriteFusedPly(ply, points);
  const std::string mesh_path = JoinPaths(dir, "meshed-poisson.ply");
  EXPECT_COLMAP_OK("poisson_mesher --input_path " + ply + " --output_path " + mesh_path +
                       " --PoissonMeshing.depth 6 --PoissonMeshing.trim 0 "
                       "--PoissonMeshing.num_threads 1",  // OpenMP threads spin on a loaded machine
                   dir);
  const TriangleMesh mesh = ReadMeshPly(mesh_path);
  ASSERT_GT(mesh.vertices.size(), 100u);
  ASSERT_GT(mesh.faces.size(), 100u);
  EXPECT_EQ(mesh.colors.size(), mesh.vertices.size());
  double max_error = 0;
  for (const Eigen::Vector3f& v : mesh.vertices) {
    max_error = std::max(max_error, std::abs(static_cast<double>(v.norm()) - 1.0));
  }
  // Octree depth 6 over the unit sphere: cells of about 2/64 m.
  EXPECT_LT(max_error, 0.05);
  RecordProperty("poisson_max_radius_error", Format(max_error));
  // And our mesh writer's output reads back the same.
  WriteMeshPly(JoinPaths(dir, "copy.ply"), mesh);
  const TriangleMesh copy = ReadMeshPly(JoinPaths(dir, "copy.ply"));
  EXPECT_EQ(copy.vertices, mesh.vertices);
  EXPECT_EQ(copy.faces, mesh.faces);
}

}  // namespace
}  // namespace hairmvs
