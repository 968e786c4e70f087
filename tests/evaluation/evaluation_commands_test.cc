// import_ground_truth, evaluate_depth and evaluate_mesh on a tiny synthetic scene whose truth is
// known in closed form: a plane of parallel straight strands 0.1 mm apart, seen by two cameras.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <limits>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/ply.h"
#include "colmap_ext/reconstruction.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/evaluation.h"
#include "src/core/depth_geometry.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/test_util.h"
#include "src/evaluation/ground_truth.h"

namespace hairmvs {
namespace {

constexpr int kWidth = 64;
constexpr int kHeight = 48;
constexpr double kPlaneZ = 0.5;       // world z of the hair plane
constexpr double kStrandGap = 1e-4;   // strands 0.1 mm apart along world x
constexpr double kHairHalfX = 0.03, kHairHalfY = 0.02;

struct Scene {
  std::string dir, gt, workspace;
  GroundTruthCameras cameras;
};

Scene MakeScene(const std::string& name) {
  Scene scene;
  scene.dir = testing_util::MakeTestDir("eval_" + name);
  scene.gt = JoinPaths(scene.dir, "gt");
  scene.workspace = JoinPaths(scene.dir, "dense");
  GroundTruthCameras& cameras = scene.cameras;
  cameras.K << 400, 0, 32, 0, 400, 24, 0, 0, 1;
  cameras.width = kWidth;
  cameras.height = kHeight;
  const Eigen::Vector3d centres[2] = {{0, 0, 0}, {-0.03, 0.01, 0.02}};
  const double angles[2] = {0.0, -0.06};
  Reconstruction model;
  Camera camera;
  camera.camera_id = 1;
  camera.model_id = 1;  // PINHOLE
  camera.width = kWidth;
  camera.height = kHeight;
  camera.params = {400, 400, 32, 24};
  model.cameras[1] = camera;
  CreateDirs(JoinPaths(scene.workspace, "images"));
  CreateDirs(JoinPaths(scene.workspace, "sparse"));
  for (int i = 0; i < 2; ++i) {
    const std::string image_name = "v" + std::to_string(i) + ".png";
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(angles[i], Eigen::Vector3d::UnitY()).toRotationMatrix();
    const Eigen::Vector3d t = -R * centres[i];
    cameras.names.push_back(image_name);
    cameras.R.push_back(R);
    cameras.t.push_back(t);
    Image image;
    image.image_id = i + 1;
    image.camera_id = 1;
    image.name = image_name;
    image.cam_from_world_rotation = Eigen::Quaterniond(R);
    image.cam_from_world_translation = t;
    model.images[image.image_id] = image;
    cv::imwrite(JoinPaths(scene.workspace, "images", image_name),
                cv::Mat(kHeight, kWidth, CV_8UC3, cv::Scalar(30, 40, 50)));
    // The true depth: ray / plane intersection; hair inside a rectangle of the plane.
    GroundTruthView view;
    view.depth = FloatMap(kWidth, kHeight, 1, 0.0f);
    view.label.assign(kWidth * kHeight, kLabelBackground);
    for (int r = 0; r < kHeight; ++r) {
      for (int c = 0; c < kWidth; ++c) {
        const Eigen::Vector3d ray = R.transpose() * BackProjectPixel(cameras.K, c, r, 1.0);
        const double s = (kPlaneZ - centres[i].z()) / ray.z();
        const Eigen::Vector3d X = centres[i] + s * ray;
        if (std::abs(X.x()) > kHairHalfX || std::abs(X.y()) > kHairHalfY) continue;
        view.depth.At(r, c) = static_cast<float>((R * X + t).z());
        view.label[r * kWidth + c] = kLabelHair;
      }
    }
    WriteGroundTruthView(scene.gt, image_name, view);
  }
  model.SortImageOrder();
  WriteReconstruction(model, JoinPaths(scene.workspace, "sparse"), ModelFormat::kText);
  WriteGroundTruthCameras(scene.gt, cameras);
  // Straight strands along y, points 6 mm apart, covering the hair rectangle and more.
  GroundTruthStrands strands;
  strands.offsets.push_back(0);
  for (double x = -kHairHalfX - 0.005; x <= kHairHalfX + 0.005; x += kStrandGap) {
    for (double y = -kHairHalfY - 0.006; y <= kHairHalfY + 0.006; y += 0.006) {
      strands.points.emplace_back(x, y, kPlaneZ);
    }
    strands.offsets.push_back(strands.points.size());
  }
  WriteGroundTruthStrands(scene.gt, strands);
  return scene;
}

DepthEvaluationOptions FastDepthOptions() {
  DepthEvaluationOptions options;
  options.strand_spacing_m = 2e-3;  // straight strands: the polyline is exact anyway
  return options;
}

// A scene's true maps imported into a new workspace, with one view's truth and the path of its
// imported depth map, for tests that write that map again with errors of their own.
struct ImportedView {
  Scene scene;
  std::string workspace;
  GroundTruthView truth;
  std::string depth_map_path;
};

ImportedView ImportView(const std::string& scene_name, const std::string& image_name) {
  ImportedView imported;
  imported.scene = MakeScene(scene_name);
  imported.workspace = JoinPaths(imported.scene.dir, "imported");
  ImportGroundTruth(imported.scene.gt, imported.scene.workspace, imported.workspace,
                    ImportGroundTruthOptions());
  imported.truth = ReadGroundTruthView(imported.scene.gt, image_name);
  imported.depth_map_path = Workspace::Read(imported.workspace).DepthMapPath(image_name);
  return imported;
}

TEST(EvaluationCommands, ImportThenEvaluateTheTruth) {
  const Scene scene = MakeScene("truth");
  const std::string out = JoinPaths(scene.dir, "imported");
  ImportGroundTruthOptions import_options;
  const ImportGroundTruthResult imported =
      ImportGroundTruth(scene.gt, scene.workspace, out, import_options);
  EXPECT_EQ(imported.num_views, 2);
  EXPECT_TRUE(std::filesystem::is_symlink(JoinPaths(out, "images")));
  {
    // A map left empty (here v1's truth holds no hair, and only hair is kept) is written, but
    // named in a warning.
    const std::string gt_copy = JoinPaths(scene.dir, "gt_no_hair_in_v1");
    std::filesystem::copy(scene.gt, gt_copy);
    GroundTruthView no_hair = ReadGroundTruthView(gt_copy, "v1.png");
    std::replace(no_hair.label.begin(), no_hair.label.end(), kLabelHair, kLabelSkin);
    WriteGroundTruthView(gt_copy, "v1.png", no_hair);
    ImportGroundTruthOptions hair_only;
    hair_only.hair_only = true;
    ::testing::internal::CaptureStderr();
    ImportGroundTruth(gt_copy, scene.workspace, JoinPaths(scene.dir, "empty"), hair_only);
    const std::string log = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(log.find("1 of the 2 depth maps written are empty: v1.png (no true depth of the "
                       "kept labels)"),
              std::string::npos)
        << log;
  }
  const Workspace workspace = Workspace::Read(out);
  const std::string v1 = workspace.DepthMapPath("v1.png");
  const FloatMap depth = ReadMat(v1);
  const GroundTruthView truth = ReadGroundTruthView(scene.gt, "v1.png");
  EXPECT_EQ(depth.Data(), truth.depth.Data());
  // Normals of the plane z = 0.5 in camera 1's frame: R * (0, 0, -1).
  const FloatMap normals = ReadMat(workspace.NormalMapPath("v1.png"));
  const Eigen::Vector3d expected = scene.cameras.R[1] * Eigen::Vector3d(0, 0, -1);
  const int r = kHeight / 2, c = kWidth / 2;
  ASSERT_GT(depth.At(r, c), 0);
  EXPECT_NEAR(normals.At(r, c, 0), expected.x(), 1e-3);
  EXPECT_NEAR(normals.At(r, c, 2), expected.z(), 1e-3);

  const DepthEvaluationResult result = EvaluateDepthMaps(out, scene.gt, FastDepthOptions());
  ASSERT_EQ(result.views.size(), 2u);
  EXPECT_GT(result.overall.num_hair_pixels, 1000);
  EXPECT_DOUBLE_EQ(result.overall.completeness, 1.0);
  EXPECT_NEAR(result.overall.mean_abs_error_mm, 0.0, 1e-9);
  EXPECT_DOUBLE_EQ(result.overall.within_1mm, 1.0);
  EXPECT_NEAR(result.overall.median_signed_error_mm, 0.0, 1e-9);
  // On the plane of strands 0.1 mm apart: at most 0.05 mm from one (float depths: + ~1e-4 mm).
  EXPECT_LT(result.overall.accuracy_3d_mean_mm, 0.0502);
  EXPECT_GT(result.overall.accuracy_3d_mean_mm, 0.01);
  EXPECT_TRUE(ExistsFile(JoinPaths(out, "stereo", "evaluation", "v0.png.error.png")));
  const auto json = nlohmann::json::parse(ReadTextFile(result.json_path));
  EXPECT_EQ(json["views"].size(), 2u);
  EXPECT_EQ(json["overall"]["num_hair_pixels"].get<long>(), result.overall.num_hair_pixels);
  EXPECT_NE(result.Table().find("overall"), std::string::npos);

  // A view whose map holds no depth: 0% complete, and its errors are no figure (NaN: nan in
  // the table, null in the JSON), not 0 mm.
  WriteMat(v1, FloatMap(depth.Width(), depth.Height(), 1, 0.0f));
  const DepthEvaluationResult empty = EvaluateDepthMaps(out, scene.gt, FastDepthOptions());
  ASSERT_EQ(empty.views.size(), 2u);
  const DepthMetrics& without = empty.views[1];
  EXPECT_EQ(without.name, "v1.png");
  EXPECT_EQ(without.completeness, 0.0);
  EXPECT_TRUE(std::isnan(without.median_abs_error_mm));
  EXPECT_TRUE(std::isnan(without.accuracy_3d_median_mm));
  EXPECT_TRUE(nlohmann::json::parse(ReadTextFile(empty.json_path))["views"][1]
                  ["median_abs_error_mm"]
                      .is_null());
  EXPECT_FALSE(std::isnan(empty.overall.median_abs_error_mm));

  // A view without its map is named as left out of the overall figures; a view asked for that
  // the workspace lacks is an error, not a missing file.
  std::filesystem::remove(v1);
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(EvaluateDepthMaps(out, scene.gt, FastDepthOptions()).views.size(), 1u);
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("1 of 2 views are not evaluated, for want of their file (e.g. " +
                     v1 + "): v1.png"),
            std::string::npos)
      << log;
  DepthEvaluationOptions unknown = FastDepthOptions();
  unknown.image_names = {"v9.png"};
  EXPECT_EQ(testing_util::ErrorOf([&] { EvaluateDepthMaps(out, scene.gt, unknown); }),
            "Image with name `v9.png` (--image_names) does not exist in workspace " + out);
}

TEST(EvaluationCommands, NoiseHolesAndHalfResolution) {
  const Scene scene = MakeScene("noise");
  const std::string out = JoinPaths(scene.dir, "noisy");
  ImportGroundTruthOptions import_options;
  import_options.noise_m = 1e-3;
  import_options.seed = 3;
  ImportGroundTruth(scene.gt, scene.workspace, out, import_options);
  // Knock out every other row of v0: completeness 50%.
  const std::string v0 = Workspace::Read(out).DepthMapPath("v0.png");
  FloatMap depth = ReadMat(v0);
  for (int r = 0; r < kHeight; r += 2) {
    for (int c = 0; c < kWidth; ++c) depth.At(r, c) = 0;
  }
  WriteMat(v0, depth);
  const DepthEvaluationResult result = EvaluateDepthMaps(out, scene.gt, FastDepthOptions());
  EXPECT_NEAR(result.views[0].completeness, 0.5, 0.02);
  EXPECT_DOUBLE_EQ(result.views[1].completeness, 1.0);
  // |N(0, 1 mm)|: mean 0.80 mm, median 0.67 mm, 68% within 1 mm, 95% within 2 mm.
  EXPECT_NEAR(result.overall.mean_abs_error_mm, 0.80, 0.06);
  EXPECT_NEAR(result.overall.median_abs_error_mm, 0.67, 0.07);
  EXPECT_NEAR(result.overall.within_1mm, 0.68, 0.04);
  EXPECT_NEAR(result.overall.within_2mm, 0.95, 0.02);
  EXPECT_GT(result.overall.accuracy_3d_median_mm, 0.4);

  // Half-resolution depth maps (32 x 24) of the truth, exact at their own pixel centres: each
  // sampled true pixel is compared where the ray through its centre meets the map, between the
  // map's pixel centres, so the errors stay ~0 but at the hair's edge (0.004 mm on v1). v1 sees
  // the plane tilted (its depth changes by 0.07 mm per true pixel): a map pixel's centre lies
  // on the truth's pixel edges, and its depth compared with the true pixel beside it, half a
  // true pixel off, erred by 0.036 mm there.
  const std::string out2 = JoinPaths(scene.dir, "half");
  ImportGroundTruth(scene.gt, scene.workspace, out2, ImportGroundTruthOptions());
  Eigen::Matrix3d K_half = scene.cameras.K;
  K_half.row(0) *= 0.5;
  K_half.row(1) *= 0.5;
  for (int i = 0; i < 2; ++i) {
    const std::string name = "v" + std::to_string(i) + ".png";
    const Eigen::Matrix3d& R = scene.cameras.R[i];
    const Eigen::Vector3d& t = scene.cameras.t[i];
    const Eigen::Vector3d centre = -R.transpose() * t;
    FloatMap half(kWidth / 2, kHeight / 2, 1, 0.0f);
    for (int r = 0; r < kHeight / 2; ++r) {
      for (int c = 0; c < kWidth / 2; ++c) {
        // Exact plane depth through the half-resolution pixel centre.
        const Eigen::Vector3d ray = R.transpose() * BackProjectPixel(K_half, c, r, 1.0);
        const Eigen::Vector3d X = centre + ray * ((kPlaneZ - centre.z()) / ray.z());
        if (std::abs(X.x()) <= kHairHalfX && std::abs(X.y()) <= kHairHalfY) {
          half.At(r, c) = static_cast<float>((R * X + t).z());
        }
      }
    }
    WriteMat(Workspace::Read(out2).DepthMapPath(name), half);
    DepthEvaluationOptions options = FastDepthOptions();
    options.image_names = {name};
    const DepthEvaluationResult half_result = EvaluateDepthMaps(out2, scene.gt, options);
    EXPECT_EQ(half_result.views[0].num_hair_pixels, [&] {
      long n = 0;
      for (float d : half.Data()) n += d > 0;
      return n;
    }()) << name;
    EXPECT_LT(half_result.overall.mean_abs_error_mm, 0.01) << name;
    EXPECT_LT(half_result.overall.accuracy_3d_mean_mm, 0.0502) << name;
  }
}

// With --max_points_3d_per_view, each view's sample stands for its pixels in the overall 3D
// figures: v0 keeps a tenth of its rows, 5 mm behind the truth, v1 all of them, exact. Counted
// per sample, v0's 5 mm would weigh as much as all of v1.
TEST(EvaluationCommands, Overall3DFiguresWeighEachViewByItsPixels) {
  const Scene scene = MakeScene("weights");
  const std::string out = JoinPaths(scene.dir, "imported");
  ImportGroundTruth(scene.gt, scene.workspace, out, ImportGroundTruthOptions());
  const std::string v0 = Workspace::Read(out).DepthMapPath("v0.png");
  FloatMap depth = ReadMat(v0);
  for (int r = 0; r < kHeight; ++r) {
    for (int c = 0; c < kWidth; ++c) {
      float& d = depth.At(r, c);
      if (d > 0) d = r % 10 == 0 ? d + 5e-3f : 0.0f;
    }
  }
  WriteMat(v0, depth);
  DepthEvaluationOptions options = FastDepthOptions();
  options.max_points_3d_per_view = 20;
  const DepthEvaluationResult result = EvaluateDepthMaps(out, scene.gt, options);
  ASSERT_EQ(result.views.size(), 2u);
  double pixels = 0, weighted = 0;
  for (const DepthMetrics& view : result.views) {
    EXPECT_EQ(view.num_points_3d, 20) << view.name;
    pixels += view.num_with_depth;
    weighted += view.num_with_depth * view.accuracy_3d_mean_mm;
  }
  EXPECT_GT(result.views[0].accuracy_3d_mean_mm, 4.0);
  EXPECT_LT(result.views[1].accuracy_3d_mean_mm, 0.06);
  EXPECT_NEAR(result.overall.accuracy_3d_mean_mm, weighted / pixels, 1e-9);
  EXPECT_LT(result.overall.accuracy_3d_mean_mm, 1.0);
  // The median of the copies: v1's, the larger part.
  EXPECT_LT(result.overall.accuracy_3d_median_mm, 0.06);
}

// Depths beyond the hair's silhouette (where the truth is background) are errors of the map
// that no true depth measures per pixel: they count in the 3D figures (distance to the nearest
// strand) and in their own share, and leave the per-pixel figures as they were.
TEST(EvaluationCommands, DepthsOnTheBackgroundCountIn3D) {
  ImportedView imported = ImportView("background", "v0.png");
  DepthEvaluationOptions options = FastDepthOptions();
  options.image_names = {"v0.png"};
  options.max_points_3d_per_view = 0;  // every point
  const DepthEvaluationResult exact = EvaluateDepthMaps(imported.workspace, imported.scene.gt,
                                                        options);
  EXPECT_EQ(exact.overall.num_background_depths, 0);
  EXPECT_LT(exact.overall.accuracy_3d_mean_mm, 0.06);
  // Every background pixel gets a depth 20 mm in front of the plane the hair lies in: at least
  // 20 mm from every strand.
  FloatMap depth = ReadMat(imported.depth_map_path);
  long spilled = 0, hair = 0;
  for (int r = 0; r < kHeight; ++r) {
    for (int c = 0; c < kWidth; ++c) {
      if (imported.truth.label[r * kWidth + c] == kLabelBackground) {
        depth.At(r, c) = static_cast<float>(kPlaneZ - 0.02);
        ++spilled;
      } else {
        hair += depth.At(r, c) > 0;
      }
    }
  }
  ASSERT_GT(spilled, 100);
  WriteMat(imported.depth_map_path, depth);
  const DepthEvaluationResult result =
      EvaluateDepthMaps(imported.workspace, imported.scene.gt, options);
  const DepthMetrics& m = result.overall;
  EXPECT_EQ(m.num_background_depths, spilled);
  EXPECT_NEAR(m.background_depth_fraction, static_cast<double>(spilled) / (spilled + hair), 1e-12);
  EXPECT_EQ(m.num_points_3d, spilled + hair);
  // The mean over all points: the spilled share at >= 20 mm (up to the plane's 5 mm margin of
  // strands beyond the hair, at 20 mm in front still >= 20 mm).
  EXPECT_GT(m.accuracy_3d_mean_mm, 19.9 * spilled / (spilled + hair));
  EXPECT_EQ(m.num_with_depth, exact.overall.num_with_depth);
  EXPECT_DOUBLE_EQ(m.median_abs_error_mm, exact.overall.median_abs_error_mm);
  EXPECT_DOUBLE_EQ(m.completeness, exact.overall.completeness);
  EXPECT_NE(result.Table().find("    bg "), std::string::npos) << result.Table();
}

TEST(EvaluationCommands, SignedErrorsNearTheSilhouetteAndInside) {
  // v0's depths 3 mm behind the truth within 4 px of the background, 1 mm in front further in;
  // the distance to the nearest background pixel by brute force.
  const ImportedView imported = ImportView("silhouette", "v0.png");
  const Scene& scene = imported.scene;
  const std::string& out = imported.workspace;
  const GroundTruthView& truth = imported.truth;
  const std::string& v0 = imported.depth_map_path;
  FloatMap depth = ReadMat(v0);
  long num_near = 0, num_hair = 0;
  for (int r = 0; r < kHeight; ++r) {
    for (int c = 0; c < kWidth; ++c) {
      if (truth.label[r * kWidth + c] != kLabelHair) continue;
      double nearest = std::numeric_limits<double>::infinity();
      for (int br = 0; br < kHeight; ++br) {
        for (int bc = 0; bc < kWidth; ++bc) {
          if (truth.label[br * kWidth + bc] == kLabelBackground) {
            nearest = std::min(nearest, std::hypot(br - r, bc - c));
          }
        }
      }
      const bool near = nearest <= 4.0;
      depth.At(r, c) += near ? 3e-3f : -1e-3f;
      num_near += near;
      ++num_hair;
    }
  }
  WriteMat(v0, depth);
  DepthEvaluationOptions options = FastDepthOptions();
  options.image_names = {"v0.png"};
  options.silhouette_band_px = 4;
  const DepthEvaluationResult result = EvaluateDepthMaps(out, scene.gt, options);
  const DepthMetrics& m = result.overall;
  ASSERT_EQ(m.num_with_depth, num_hair);
  ASSERT_GT(num_near, num_hair / 4);
  ASSERT_LT(num_near, num_hair / 2);
  EXPECT_NEAR(m.silhouette_fraction, static_cast<double>(num_near) / num_hair, 1e-12);
  EXPECT_NEAR(m.silhouette_median_signed_error_mm, 3.0, 1e-3);  // float depths
  EXPECT_NEAR(m.silhouette_median_abs_error_mm, 3.0, 1e-3);
  EXPECT_NEAR(m.interior_median_signed_error_mm, -1.0, 1e-3);
  EXPECT_NEAR(m.interior_median_abs_error_mm, 1.0, 1e-3);
  // Most pixels are inside: the overall signed median is theirs.
  EXPECT_NEAR(m.median_signed_error_mm, -1.0, 1e-3);
  EXPECT_NEAR(m.median_abs_error_mm, 1.0, 1e-3);
  const auto json = nlohmann::json::parse(ReadTextFile(result.json_path));
  EXPECT_NEAR(json["overall"]["silhouette_median_signed_error_mm"].get<double>(), 3.0, 1e-3);
  EXPECT_NE(result.Table().find("sil_med"), std::string::npos);
  // The signed picture (BGR; float depths: +-1 per channel): 3 mm behind of the 10 mm scale
  // is light red, 1 mm in front light blue.
  const cv::Mat signed_image = cv::imread(
      JoinPaths(out, "stereo", "evaluation", "v0.png.signed_error.png"), cv::IMREAD_COLOR);
  ASSERT_FALSE(signed_image.empty());
  auto expect_colour = [&](int r, int c, cv::Vec3b expected) {
    const cv::Vec3b actual = signed_image.at<cv::Vec3b>(r, c);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(actual[k], expected[k], 1) << r << " " << c;
  };
  expect_colour(kHeight / 2, kWidth / 2, cv::Vec3b(255, 230, 230));
  for (int c = 0; c < kWidth; ++c) {  // the first hair pixel of the middle row is near
    if (truth.label[(kHeight / 2) * kWidth + c] != kLabelHair) continue;
    expect_colour(kHeight / 2, c, cv::Vec3b(179, 179, 255));
    break;
  }
  expect_colour(0, 0, cv::Vec3b(0, 0, 0));  // background

  options.silhouette_band_px = -1;
  std::string error;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("silhouette_band_px"), std::string::npos) << error;
}

// v0's depths 2 mm behind the truth plus a checkerboard of +-1 mm: over a 5 x 5 window the
// checkerboard averages to +-0.04 mm (13 squares of one sign, 12 of the other), so the smooth
// part is 2 mm and the rest 1 mm, up to that and the partial windows at the hair's edges.
TEST(EvaluationCommands, ErrorSplitIntoItsSmoothPartAndTheRest) {
  const ImportedView v0 = ImportView("smooth_error", "v0.png");
  const FloatMap exact = ReadMat(v0.depth_map_path);
  DepthEvaluationOptions options = FastDepthOptions();
  options.image_names = {"v0.png"};
  options.write_error_images = false;
  options.smooth_error_window_px = 5;
  auto evaluate_with_checkerboard = [&](float checker_m) {
    FloatMap depth = exact;
    for (int r = 0; r < kHeight; ++r) {
      for (int c = 0; c < kWidth; ++c) {
        if (v0.truth.label[r * kWidth + c] != kLabelHair) continue;
        depth.At(r, c) += 2e-3f + ((r + c) % 2 == 0 ? checker_m : -checker_m);
      }
    }
    WriteMat(v0.depth_map_path, depth);
    return EvaluateDepthMaps(v0.workspace, v0.scene.gt, options);
  };
  DepthMetrics m = evaluate_with_checkerboard(1e-3f).overall;
  EXPECT_NEAR(m.smooth_median_abs_error_mm, 2.0, 0.05);
  EXPECT_NEAR(m.rough_median_abs_error_mm, 1.0, 0.05);
  EXPECT_NEAR(m.median_abs_error_mm, 2.0, 1e-3);  // 1 or 3 mm, as many of each (+-1)
  // A smooth error has no rest (float depths: 1e-4 mm).
  m = evaluate_with_checkerboard(0.0f).overall;
  EXPECT_NEAR(m.smooth_median_abs_error_mm, 2.0, 1e-3);
  EXPECT_NEAR(m.rough_median_abs_error_mm, 0.0, 1e-3);
  // A 1 x 1 window: the smooth part is the error itself.
  options.smooth_error_window_px = 1;
  const DepthEvaluationResult result = evaluate_with_checkerboard(1e-3f);
  m = result.overall;
  EXPECT_DOUBLE_EQ(m.smooth_median_abs_error_mm, m.median_abs_error_mm);
  EXPECT_NEAR(m.rough_median_abs_error_mm, 0.0, 1e-9);
  EXPECT_NE(result.Table().find("smooth"), std::string::npos);
  const auto json = nlohmann::json::parse(ReadTextFile(result.json_path));
  EXPECT_NEAR(json["overall"]["rough_median_abs_error_mm"].get<double>(), 0.0, 1e-9);

  // Off: no split, so no figure (NaN: nan in the table, null in the JSON), not 0 mm.
  options.smooth_error_window_px = 0;
  m = EvaluateDepthMaps(v0.workspace, v0.scene.gt, options).overall;
  EXPECT_TRUE(std::isnan(m.smooth_median_abs_error_mm));
  EXPECT_TRUE(std::isnan(m.rough_median_abs_error_mm));
  options.smooth_error_window_px = 4;
  std::string error;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("smooth_error_window_px"), std::string::npos) << error;
  options.smooth_error_window_px = 1001;  // wider than any image: refused before the maps
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("smooth_error_window_px must be 0 or odd, at most 999"), std::string::npos)
      << error;
  options.smooth_error_window_px = 0;
  options.layer_window_px = 1001;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("layer_window_px must be 0 or odd, at most 999"), std::string::npos)
      << error;
}

// A workspace whose v1 is off its true pose, as a mapper's poses are: 5 mm nearer the hair
// along its axis and turned 0.4 degrees (2.8 px here). import_ground_truth gives the true maps
// their true poses back. The off-pose camera's own exact depths, compared at the true pixel of
// the same index, are 5 mm off; compared in the true camera, they meet the truth.
TEST(EvaluationCommands, DepthsOfAnOffPoseCameraComparedInTheTrueCamera) {
  const Scene scene = MakeScene("off_pose");
  const std::string sparse = JoinPaths(scene.workspace, "sparse");
  Reconstruction model = ReadReconstruction(sparse);
  Image* v1 = nullptr;
  for (auto& [id, image] : model.images) {
    if (image.name == "v1.png") v1 = &image;
  }
  ASSERT_NE(v1, nullptr);
  const Eigen::Vector3d true_centre = v1->ProjectionCenter();
  const Eigen::Vector3d centre = true_centre + 5e-3 * v1->ViewingDirection();
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.4 * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix() * v1->R();
  const Eigen::Vector3d t = -R * centre;
  v1->cam_from_world_rotation = Eigen::Quaterniond(R);
  v1->cam_from_world_translation = t;
  WriteReconstruction(model, sparse, ModelFormat::kText);

  const std::string out = JoinPaths(scene.dir, "off_pose");
  ImportGroundTruth(scene.gt, scene.workspace, out, ImportGroundTruthOptions());
  const Reconstruction imported = ReadReconstruction(JoinPaths(out, "sparse"));
  for (const auto& [id, image] : imported.images) {
    if (image.name == "v1.png") {
      EXPECT_LT((image.ProjectionCenter() - true_centre).norm(), 1e-12);
    }
  }
  DepthEvaluationOptions options = FastDepthOptions();
  options.image_names = {"v1.png"};
  for (bool in_true_cameras : {true, false}) {
    options.in_true_cameras = in_true_cameras;
    EXPECT_LT(EvaluateDepthMaps(out, scene.gt, options).overall.mean_abs_error_mm, 1e-3);
  }

  WriteReconstruction(model, JoinPaths(out, "sparse"), ModelFormat::kText);
  FloatMap depth(kWidth, kHeight, 1, 0.0f);
  for (int r = 0; r < kHeight; ++r) {
    for (int c = 0; c < kWidth; ++c) {
      const Eigen::Vector3d ray = R.transpose() * BackProjectPixel(scene.cameras.K, c, r, 1.0);
      const Eigen::Vector3d X = centre + ray * ((kPlaneZ - centre.z()) / ray.z());
      if (std::abs(X.x()) > kHairHalfX || std::abs(X.y()) > kHairHalfY) continue;
      depth.At(r, c) = static_cast<float>((R * X + t).z());
    }
  }
  WriteMat(Workspace::Read(out).DepthMapPath("v1.png"), depth);
  options.in_true_cameras = true;
  const DepthMetrics in_true = EvaluateDepthMaps(out, scene.gt, options).overall;
  // Each true pixel is compared where its ray meets the map, between the map's pixel centres:
  // exact but at the hair's edge, where the map's pixels beside have no depth and the nearest
  // one's is taken (up to half a pixel, 0.6 mm on the plane, which v1 sees 3.4 degrees off
  // fronto-parallel: 0.04 mm).
  EXPECT_LT(in_true.mean_abs_error_mm, 0.01);
  EXPECT_NEAR(in_true.median_signed_error_mm, 0.0, 0.02);
  // The rows the turn moves in and out of the hair: the same-index misses of a 2.8 px shift.
  EXPECT_GT(in_true.completeness, 0.9);
  options.in_true_cameras = false;
  const DepthMetrics same_index = EvaluateDepthMaps(out, scene.gt, options).overall;
  // Either way the hair pixels are the true ones, each once: with or without a depth, not
  // where the map's depths happen to land.
  EXPECT_EQ(in_true.num_hair_pixels, same_index.num_hair_pixels);
  // A map covering only part of the hair: the true hair pixels its rays do not meet count as
  // missing in the true camera too.
  FloatMap half = depth;
  for (int r = 0; r < kHeight; ++r) {
    for (int c = kWidth / 2; c < kWidth; ++c) half.At(r, c) = 0.0f;
  }
  WriteMat(Workspace::Read(out).DepthMapPath("v1.png"), half);
  options.in_true_cameras = true;
  const DepthMetrics half_in_true = EvaluateDepthMaps(out, scene.gt, options).overall;
  EXPECT_EQ(half_in_true.num_hair_pixels, same_index.num_hair_pixels);
  EXPECT_LT(half_in_true.completeness, 0.7 * in_true.completeness);
  EXPECT_LT(half_in_true.mean_abs_error_mm, 0.05);
  WriteMat(Workspace::Read(out).DepthMapPath("v1.png"), depth);
  options.in_true_cameras = false;
  EXPECT_NEAR(same_index.median_signed_error_mm, -5.0, 0.1);
  // Points on the plane either way (the map's pixel centres, or where the true rays meet the
  // map), so within half the strands' spacing of a strand: 0.05 mm.
  EXPECT_LT(same_index.accuracy_3d_mean_mm, 0.05);
  EXPECT_LT(in_true.accuracy_3d_mean_mm, 0.05);

  // The data term of the off-pose camera, cheapest at its own exact depth at each coarse pixel
  // (4 x 4 image pixels, labels 1 mm apart): in the true camera its true depths are carried
  // into the off-pose one and meet that label; at the same pixels they lie 5 mm behind.
  CostVolume volume;
  volume.cost = FloatMap(kWidth / 4, kHeight / 4, 80);
  for (int k = 0; k < 80; ++k) volume.label_depths.push_back(0.44 + 1e-3 * k);
  Eigen::Matrix3d K_coarse = scene.cameras.K;
  K_coarse.topRows(2) *= 0.25;
  for (int r = 0; r < kHeight / 4; ++r) {
    for (int c = 0; c < kWidth / 4; ++c) {
      const Eigen::Vector3d ray = R.transpose() * BackProjectPixel(K_coarse, c, r, 1.0);
      const double z = (R * (centre + ray * ((kPlaneZ - centre.z()) / ray.z())) + t).z();
      const double cheapest = (z - 0.44) / 1e-3;
      for (int k = 0; k < 80; ++k) volume.cost.At(r, c, k) = std::abs(k - cheapest);
    }
  }
  const std::string volumes = JoinPaths(out, "stereo", "cost_volumes");
  WriteCostVolume(JoinPaths(volumes, "v1.png.coarse.bin"),
                  JoinPaths(volumes, "v1.png.coarse.depths.txt"), volume);
  DataTermEvaluationOptions data_term_options;
  data_term_options.image_names = {"v1.png"};
  const DataTermMetrics data_term_in_true =
      EvaluateDataTerm(out, scene.gt, data_term_options).overall;
  data_term_options.in_true_cameras = false;
  const DataTermMetrics data_term_same =
      EvaluateDataTerm(out, scene.gt, data_term_options).overall;
  EXPECT_GT(data_term_in_true.num_pixels, 80);
  // The cheapest label rounds the exact depth at the coarse pixel's centre to 1 mm; the true
  // depths of its image pixels spread 0.2 mm about it.
  EXPECT_LT(data_term_in_true.median_abs_error_mm, 0.6);
  EXPECT_NEAR(data_term_same.median_abs_error_mm, 5.0, 0.6);

  // A true camera missing from gt/cameras.npz is named.
  GroundTruthCameras only_v0 = scene.cameras;
  only_v0.names.pop_back();
  only_v0.R.pop_back();
  only_v0.t.pop_back();
  WriteGroundTruthCameras(scene.gt, only_v0);
  options.in_true_cameras = true;
  try {
    EvaluateDepthMaps(out, scene.gt, options);
    ADD_FAILURE() << "no error for a missing true camera";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cameras.npz: no camera named v1.png"),
              std::string::npos)
        << e.what();
  }
  // No cameras.npz at all: named, with the way to compare at the same pixels.
  std::filesystem::remove(JoinPaths(scene.gt, "cameras.npz"));
  const std::string no_cameras =
      testing_util::ErrorOf([&] { EvaluateDepthMaps(out, scene.gt, options); });
  EXPECT_NE(no_cameras.find("Missing " + JoinPaths(scene.gt, "cameras.npz")), std::string::npos)
      << no_cameras;
  EXPECT_NE(no_cameras.find("--in_true_cameras 0"), std::string::npos) << no_cameras;
  options.in_true_cameras = false;
  EXPECT_NO_THROW(EvaluateDepthMaps(out, scene.gt, options));
  // Nor does import_ground_truth need it: the workspace's poses are then kept.
  const std::string kept = JoinPaths(scene.dir, "kept_poses");
  ImportGroundTruth(scene.gt, scene.workspace, kept, ImportGroundTruthOptions());
  for (const auto& [id, image] : ReadReconstruction(JoinPaths(kept, "sparse")).images) {
    if (image.name == "v1.png") {
      EXPECT_LT((image.ProjectionCenter() - centre).norm(), 1e-12);
    }
  }
}

TEST(EvaluationCommands, LayerOfTheDepthsAmongTheTrueDepthsAround) {
  // v1 sees the plane at a slant: its true depth grows by ~0.07 mm per column, so a 7 x 7
  // window holds three columns in front of its centre and three behind.
  const ImportedView imported = ImportView("layer", "v1.png");
  const Scene& scene = imported.scene;
  const std::string& out = imported.workspace;
  const GroundTruthView& truth = imported.truth;
  long num_full_windows = 0;
  for (int r = 3; r + 3 < kHeight; ++r) {
    for (int c = 3; c + 3 < kWidth; ++c) {
      bool all_hair = true;
      for (int wr = r - 3; wr <= r + 3; ++wr) {
        for (int wc = c - 3; wc <= c + 3; ++wc) {
          all_hair = all_hair && truth.label[wr * kWidth + wc] == kLabelHair;
        }
      }
      num_full_windows += all_hair;
    }
  }
  ASSERT_GT(num_full_windows, 500);
  const std::string& v1 = imported.depth_map_path;
  const FloatMap exact = ReadMat(v1);
  DepthEvaluationOptions options = FastDepthOptions();
  options.image_names = {"v1.png"};
  options.write_error_images = false;
  auto layer_with_offset = [&](float offset_m) {
    FloatMap depth = exact;
    for (float& d : depth.Data()) d = d > 0 ? d + offset_m : 0.0f;
    WriteMat(v1, depth);
    const DepthMetrics m = EvaluateDepthMaps(out, scene.gt, options).overall;
    EXPECT_EQ(m.num_layer_pixels, num_full_windows);
    return m.median_layer;
  };
  // The truth itself is the median of its window (measured: exactly; a tie between two rows
  // of one column that float rounding breaks moves it by 1 / 98).
  EXPECT_NEAR(layer_with_offset(0.0f), 0.5, 0.03);
  // 1 mm behind: every true depth of the window is in front; 1 mm in front: none.
  EXPECT_DOUBLE_EQ(layer_with_offset(1e-3f), 1.0);
  EXPECT_DOUBLE_EQ(layer_with_offset(-1e-3f), 0.0);
  // 0.1 mm behind: the window's column 1 px behind (+0.07 mm) is in front too, the next not.
  EXPECT_NEAR(layer_with_offset(1e-4f), 35.0 / 49, 0.03);

  options.layer_window_px = 0;
  EXPECT_EQ(EvaluateDepthMaps(out, scene.gt, options).overall.num_layer_pixels, 0);
  options.layer_window_px = 6;
  std::string error;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("layer_window_px"), std::string::npos) << error;
}

// Writes a cost volume for v0 on a 16 x 12 grid (4 x 4 image pixels each) with labels 5 mm
// apart from 0.45 m (label 10 = 0.5 m, v0's true depth everywhere: it looks straight at the
// plane z = 0.5), whose cheapest label is `cheapest` at every pixel.
void WriteShiftedVolume(const Scene& scene, int cheapest, double first_depth = 0.45,
                        int width = 16, int height = 12) {
  CostVolume volume;
  volume.cost = FloatMap(width, height, 32);
  for (int k = 0; k < 32; ++k) {
    volume.label_depths.push_back(first_depth + 0.005 * k);
    for (int r = 0; r < height; ++r) {
      for (int c = 0; c < width; ++c) volume.cost.At(r, c, k) = (k - cheapest) * (k - cheapest);
    }
  }
  const std::string volumes = JoinPaths(scene.workspace, "stereo", "cost_volumes");
  WriteCostVolume(JoinPaths(volumes, "v0.png.coarse.bin"),
                  JoinPaths(volumes, "v0.png.coarse.depths.txt"), volume);
}

TEST(EvaluationCommands, DataTermAtTheTruthAndShiftedFromIt) {
  const Scene scene = MakeScene("data_term");
  // The coarse pixels that are at least half hair, counted plainly.
  const GroundTruthView truth = ReadGroundTruthView(scene.gt, "v0.png");
  long half_hair = 0;
  for (int r = 0; r < 12; ++r) {
    for (int c = 0; c < 16; ++c) {
      int hair = 0;
      for (int y = 4 * r; y < 4 * r + 4; ++y) {
        for (int x = 4 * c; x < 4 * c + 4; ++x) hair += truth.label[y * kWidth + x] == kLabelHair;
      }
      half_hair += hair >= 8;
    }
  }
  ASSERT_GT(half_hair, 50);

  WriteShiftedVolume(scene, 10);
  // The workspace's cameras are the true ones: the true depths in the true cameras are those
  // at the same pixels.
  DataTermEvaluationOptions same_pixels;
  same_pixels.in_true_cameras = false;
  const DataTermMetrics at_truth_same_pixels =
      EvaluateDataTerm(scene.workspace, scene.gt, same_pixels).overall;
  EXPECT_EQ(at_truth_same_pixels.num_pixels, half_hair);
  EXPECT_NEAR(at_truth_same_pixels.median_abs_error_mm, 0.0, 1e-6);
  const DataTermEvaluationResult at_truth =
      EvaluateDataTerm(scene.workspace, scene.gt, DataTermEvaluationOptions());
  ASSERT_EQ(at_truth.views.size(), 1u);
  EXPECT_EQ(at_truth.overall.num_pixels, half_hair);
  EXPECT_EQ(at_truth.overall.num_outside_range, 0);
  EXPECT_NEAR(at_truth.overall.label_step_mm, 5.0, 1e-6);
  EXPECT_NEAR(at_truth.overall.median_abs_error_mm, 0.0, 1e-6);
  EXPECT_NEAR(at_truth.overall.median_signed_error_mm, 0.0, 1e-6);
  EXPECT_DOUBLE_EQ(at_truth.overall.within_1_label, 1.0);
  EXPECT_DOUBLE_EQ(at_truth.overall.within_5mm, 1.0);
  EXPECT_NEAR(at_truth.overall.median_true_depth_rank, 0.0, 1.0 / 31);

  // 6 labels (30 mm) behind: labels 11..21 cost less than the truth's 36.
  WriteShiftedVolume(scene, 16);
  const DataTermEvaluationResult shifted =
      EvaluateDataTerm(scene.workspace, scene.gt, DataTermEvaluationOptions());
  EXPECT_EQ(shifted.overall.num_pixels, half_hair);
  EXPECT_NEAR(shifted.overall.median_abs_error_mm, 30.0, 1e-6);
  EXPECT_NEAR(shifted.overall.median_signed_error_mm, 30.0, 1e-6);
  EXPECT_DOUBLE_EQ(shifted.overall.within_1_label, 0.0);
  EXPECT_DOUBLE_EQ(shifted.overall.within_10mm, 0.0);
  EXPECT_NEAR(shifted.overall.median_true_depth_rank, 11.0 / 31, 1e-9);
  const auto json = nlohmann::json::parse(ReadTextFile(shifted.json_path));
  EXPECT_EQ(json["overall"]["num_pixels"].get<long>(), half_hair);
  EXPECT_NEAR(json["overall"]["median_signed_error_mm"].get<double>(), 30.0, 1e-6);

  // 4 labels (20 mm) in front: the sign says so, the size does not.
  WriteShiftedVolume(scene, 6);
  const DataTermMetrics in_front =
      EvaluateDataTerm(scene.workspace, scene.gt, DataTermEvaluationOptions()).overall;
  EXPECT_NEAR(in_front.median_abs_error_mm, 20.0, 1e-6);
  EXPECT_NEAR(in_front.median_signed_error_mm, -20.0, 1e-6);

  // A volume of pyramid level 5 (2 x 2): its coarse pixels span 32 x 32 image pixels from the
  // image's corner, the lower ones reaching past its 48 rows (the image scaled to 2 x 2, as the
  // grid was taken before stop 55, gives 32 x 24 and counts all four as half hair).
  WriteShiftedVolume(scene, 10, 0.45, 2, 2);
  long half_hair_level5 = 0;
  for (int r = 0; r < 2; ++r) {
    for (int c = 0; c < 2; ++c) {
      int hair = 0, covered = 0;
      for (int y = 32 * r; y < std::min(32 * r + 32, kHeight); ++y) {
        for (int x = 32 * c; x < std::min(32 * c + 32, kWidth); ++x) {
          hair += truth.label[y * kWidth + x] == kLabelHair;
          ++covered;
        }
      }
      half_hair_level5 += 2 * hair >= covered;
    }
  }
  EXPECT_EQ(half_hair_level5, 2);
  EXPECT_EQ(EvaluateDataTerm(scene.workspace, scene.gt, DataTermEvaluationOptions())
                .overall.num_pixels,
            half_hair_level5);

  // Labels from 0.6 m: every true depth lies outside them.
  WriteShiftedVolume(scene, 10, 0.6);
  const DataTermEvaluationResult outside =
      EvaluateDataTerm(scene.workspace, scene.gt, DataTermEvaluationOptions());
  EXPECT_EQ(outside.overall.num_pixels, 0);
  EXPECT_EQ(outside.overall.num_outside_range, half_hair);
  std::filesystem::remove_all(scene.dir);
}

// Noise beyond a metre (or infinite, which wrote infinite depths) and even median windows are
// refused by name.
TEST(EvaluationCommands, ImportOptionsAreChecked) {
  ImportGroundTruthOptions options;
  std::string error;
  EXPECT_TRUE(options.Check(&error)) << error;
  for (double noise : {-1e-3, 2.0, std::numeric_limits<double>::infinity()}) {
    options.noise_m = noise;
    EXPECT_FALSE(options.Check(&error)) << noise;
    EXPECT_NE(error.find("--noise_m must be in [0, 1]"), std::string::npos) << error;
  }
  options = ImportGroundTruthOptions();
  options.median_filter_px = 8;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("--median_filter_px"), std::string::npos) << error;
}

TEST(EvaluationCommands, ImportRefusesToWriteIntoItsInputs) {
  const Scene scene = MakeScene("refuse");
  EXPECT_THROW(ImportGroundTruth(scene.gt, scene.workspace, JoinPaths(scene.workspace, "x"),
                                 ImportGroundTruthOptions()),
               Error);
  EXPECT_THROW(ImportGroundTruth(scene.gt, scene.workspace, scene.gt, ImportGroundTruthOptions()),
               Error);
}

// The bytes of a file, to tell whether a failed run left it as it was.
std::string FileBytes(const std::string& path) { return ReadTextFile(path); }

TriangleMesh HairPlaneMesh(double offset_z) {
  TriangleMesh mesh;
  const float z = static_cast<float>(kPlaneZ + offset_z);
  mesh.vertices = {{-0.03f, -0.02f, z}, {0.03f, -0.02f, z}, {0.03f, 0.02f, z}, {-0.03f, 0.02f, z}};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

// Neither evaluation writes its results over the mesh evaluated or into the ground truth
// (found writing the JSON over the mesh, and over gt/meta.json).
TEST(EvaluationCommands, EvaluationsRefuseToWriteOverTheirInputs) {
  const Scene scene = MakeScene("refuse_eval");
  const std::string mesh = JoinPaths(scene.dir, "mesh.ply");
  WriteMeshPly(mesh, HairPlaneMesh(0.0));
  const std::string mesh_bytes = FileBytes(mesh);
  MeshEvaluationOptions mesh_options;
  mesh_options.output_json = mesh;
  std::string error =
      testing_util::ErrorOf([&] { EvaluateMesh(mesh, scene.gt, "", mesh_options); });
  EXPECT_NE(error.find("--output_json " + mesh + " is the file evaluated"), std::string::npos)
      << error;
  EXPECT_EQ(FileBytes(mesh), mesh_bytes);
  mesh_options.output_json = JoinPaths(scene.gt, "meta.json");
  error = testing_util::ErrorOf([&] { EvaluateMesh(mesh, scene.gt, "", mesh_options); });
  EXPECT_NE(error.find(" lies in the ground truth folder " + scene.gt), std::string::npos)
      << error;
  EXPECT_FALSE(ExistsFile(mesh_options.output_json));

  const std::string out = JoinPaths(scene.dir, "imported");
  ImportGroundTruth(scene.gt, scene.workspace, out, ImportGroundTruthOptions());
  DepthEvaluationOptions depth_options = FastDepthOptions();
  depth_options.output_path = JoinPaths(scene.gt, "evaluation");
  error = testing_util::ErrorOf([&] { EvaluateDepthMaps(out, scene.gt, depth_options); });
  EXPECT_NE(error.find("--output_path " + depth_options.output_path + " lies in the ground "
                       "truth folder"),
            std::string::npos)
      << error;
  EXPECT_FALSE(std::filesystem::exists(depth_options.output_path));
}

// `path` cut to half its size.
void TruncateToHalf(const std::string& path) {
  std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
}

// A truth file cut short stops import_ground_truth before anything is written: no new
// workspace half made, and an existing one keeps every map of its own run (not some maps of
// the failed run's settings beside others of the old's).
TEST(EvaluationCommands, ImportStopsOnABadTruthBeforeWriting) {
  const Scene scene = MakeScene("bad_truth");
  const std::string gt_bad = JoinPaths(scene.dir, "gt_bad");
  std::filesystem::copy(scene.gt, gt_bad);
  TruncateToHalf(GroundTruthViewPath(gt_bad, "v1.png"));
  const std::string fresh = JoinPaths(scene.dir, "fresh");
  std::string error = testing_util::ErrorOf(
      [&] { ImportGroundTruth(gt_bad, scene.workspace, fresh, ImportGroundTruthOptions()); });
  EXPECT_NE(error.find(GroundTruthViewPath(gt_bad, "v1.png")), std::string::npos) << error;
  EXPECT_FALSE(std::filesystem::exists(fresh));

  const std::string out = JoinPaths(scene.dir, "imported");
  ImportGroundTruth(scene.gt, scene.workspace, out, ImportGroundTruthOptions());
  const Workspace ws = Workspace::Read(out);
  const std::string v0_map = FileBytes(ws.DepthMapPath("v0.png"));
  ImportGroundTruthOptions noisy;
  noisy.noise_m = 0.01;
  error = testing_util::ErrorOf([&] { ImportGroundTruth(gt_bad, scene.workspace, out, noisy); });
  EXPECT_NE(error.find(GroundTruthViewPath(gt_bad, "v1.png")), std::string::npos) << error;
  EXPECT_EQ(FileBytes(ws.DepthMapPath("v0.png")), v0_map);
}

// A depth map cut short stops evaluate_depth with the error pictures and the summary of the
// run before, which agree: none of the views evaluated before it has a new picture.
TEST(EvaluationCommands, EvaluationStoppedByABadMapLeavesTheOldPictures) {
  const Scene scene = MakeScene("bad_map");
  const std::string out = JoinPaths(scene.dir, "imported");
  ImportGroundTruth(scene.gt, scene.workspace, out, ImportGroundTruthOptions());
  const DepthEvaluationResult first = EvaluateDepthMaps(out, scene.gt, FastDepthOptions());
  const std::string folder = ParentPath(first.json_path);
  const std::string picture = JoinPaths(folder, "v0.png.signed_error.png");
  const std::string old_picture = FileBytes(picture), old_json = FileBytes(first.json_path);
  // v0's depths 1 cm behind (its pictures would change), v1's map cut short.
  const Workspace ws = Workspace::Read(out);
  FloatMap v0 = ReadMat(ws.DepthMapPath("v0.png"));
  for (float& d : v0.Data()) {
    if (d > 0) d += 0.01f;
  }
  WriteMat(ws.DepthMapPath("v0.png"), v0);
  TruncateToHalf(ws.DepthMapPath("v1.png"));
  const std::string error =
      testing_util::ErrorOf([&] { EvaluateDepthMaps(out, scene.gt, FastDepthOptions()); });
  EXPECT_NE(error.find(ws.DepthMapPath("v1.png")), std::string::npos) << error;
  EXPECT_EQ(FileBytes(picture), old_picture);
  EXPECT_EQ(FileBytes(first.json_path), old_json);
  // No hidden folder of the stopped run is left.
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    EXPECT_NE(entry.path().filename().string()[0], '.') << entry.path();
  }
}

TEST(EvaluationCommands, EvaluateMesh) {
  const Scene scene = MakeScene("mesh");
  MeshEvaluationOptions options;
  options.strand_spacing_m = 2e-3;
  options.face_sample_spacing_m = 1e-3;

  const std::string on_plane = JoinPaths(scene.dir, "on_plane.ply");
  WriteMeshPly(on_plane, HairPlaneMesh(0.0));
  const MeshEvaluationResult exact = EvaluateMesh(on_plane, scene.gt, "", options);
  EXPECT_EQ(exact.num_faces, 2);
  EXPECT_LT(exact.accuracy_surface.mean_mm, 0.0501);
  EXPECT_GT(exact.accuracy_surface.count, 2000);  // 24 cm^2 at one sample per mm^2
  EXPECT_DOUBLE_EQ(exact.completeness_2mm, 1.0);
  EXPECT_LT(exact.completeness_distance.p90_mm, 1e-3);
  EXPECT_TRUE(ExistsFile(on_plane + ".evaluation.json"));
  // A vertex far off (a corrupt PLY) asks for more surface samples than memory holds: refused,
  // naming the mesh.
  const std::string far_off = JoinPaths(scene.dir, "far_off.ply");
  auto far_mesh = HairPlaneMesh(0.0);
  far_mesh.vertices[0].z() = 1e30f;
  WriteMeshPly(far_off, far_mesh);
  const std::string far_error =
      testing_util::ErrorOf([&] { EvaluateMesh(far_off, scene.gt, "", options); });
  EXPECT_NE(far_error.find(far_off + ": sampling "), std::string::npos) << far_error;
  // A folder as the JSON's path is refused by Check, before the work.
  MeshEvaluationOptions to_folder = options;
  to_folder.output_json = scene.dir;
  std::string folder_error;
  EXPECT_FALSE(to_folder.Check(&folder_error));
  EXPECT_NE(folder_error.find("--output_json " + scene.dir + " is a folder"), std::string::npos)
      << folder_error;

  // 3 mm in front of the plane: accuracy 3 mm, nothing within 2 mm, everything within 5 mm.
  const std::string shifted = JoinPaths(scene.dir, "shifted.ply");
  WriteMeshPly(shifted, HairPlaneMesh(-0.003));
  const MeshEvaluationResult off = EvaluateMesh(shifted, scene.gt, scene.workspace, options);
  EXPECT_NEAR(off.accuracy_vertices.median_mm, 3.0, 1e-3);
  EXPECT_NEAR(off.accuracy_surface.median_mm, 3.0, 1e-3);
  EXPECT_NEAR(off.completeness_distance.median_mm, 3.0, 1e-3);
  EXPECT_DOUBLE_EQ(off.completeness_2mm, 0.0);
  EXPECT_DOUBLE_EQ(off.completeness_5mm, 1.0);
  EXPECT_TRUE(ExistsFile(JoinPaths(scene.workspace, "stereo", "evaluation",
                                   "mesh_evaluation.json")));

  // True cameras of another size than the true maps would back-project the visible hair to
  // the wrong place: named, as the depth evaluation names them.
  GroundTruthCameras resized = scene.cameras;
  resized.width *= 2;
  resized.height *= 2;
  WriteGroundTruthCameras(scene.gt, resized);
  const std::string error =
      testing_util::ErrorOf([&] { EvaluateMesh(on_plane, scene.gt, "", options); });
  EXPECT_NE(error.find(JoinPaths(scene.gt, "cameras.npz") + ": cameras of " +
                       std::to_string(resized.width) + " x " + std::to_string(resized.height)),
            std::string::npos)
      << error;
}

}  // namespace
}  // namespace hairmvs
