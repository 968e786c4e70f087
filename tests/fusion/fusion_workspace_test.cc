// template_fusion end to end: a COLMAP workspace with synthetic depth and normal maps of a
// torus is written to disk, RunTemplateFusion writes fused.ply(.vis) and meshed-hair.ply,
// which read back consistently, and `colmap poisson_mesher` reads our fused.ply.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/ply.h"
#include "colmap_ext/reconstruction.h"
#include "colmap_ext/test_util.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/template_fusion.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/fusion/fusion_test_scenes.h"
#include "src/core/test_util.h"

namespace hairmvs {
namespace {

using testing_util::MakeTestDir;

// Writes views as a COLMAP dense workspace; image ids are assigned in reverse so that the
// image_idx order (file order, ascending ids as we write) differs from the views' order.
void WriteWorkspace(const std::vector<FusionView>& views, const std::string& dir) {
  Reconstruction model;
  Camera camera;
  camera.camera_id = 1;
  camera.model_id = 1;  // PINHOLE
  camera.width = views[0].depth.Width();
  camera.height = views[0].depth.Height();
  camera.params = {views[0].K(0, 0), views[0].K(1, 1), views[0].K(0, 2), views[0].K(1, 2)};
  model.cameras[1] = camera;
  for (size_t i = 0; i < views.size(); ++i) {
    Image image;
    image.image_id = static_cast<uint32_t>(views.size() - i);
    image.camera_id = 1;
    image.name = views[i].name;
    image.cam_from_world_rotation = Eigen::Quaterniond(views[i].R);
    image.cam_from_world_translation = views[i].t;
    model.images[image.image_id] = image;
    cv::Mat bgr(views[i].depth.Height(), views[i].depth.Width(), CV_8UC3);
    for (int r = 0; r < bgr.rows; ++r) {
      for (int c = 0; c < bgr.cols; ++c) {
        const uint8_t v = static_cast<uint8_t>(255 * views[i].rgb.At(r, c, 0));
        bgr.at<cv::Vec3b>(r, c) = cv::Vec3b(v, v, v);
      }
    }
    CreateDirs(JoinPaths(dir, "images"));
    ASSERT_TRUE(cv::imwrite(JoinPaths(dir, "images", views[i].name), bgr));
    WriteMat(JoinPaths(dir, "stereo", "depth_maps", views[i].name + ".geometric.bin"),
             views[i].depth);
    WriteMat(JoinPaths(dir, "stereo", "normal_maps", views[i].name + ".geometric.bin"),
             views[i].normal);
  }
  model.SortImageOrder();
  CreateDirs(JoinPaths(dir, "sparse"));
  WriteReconstruction(model, JoinPaths(dir, "sparse"), ModelFormat::kBinary);
}

// The torus' views (64 x 48) and the fusion options of the tests that fuse them.
testing::SceneOptions TorusViews() {
  testing::SceneOptions scene;
  scene.width = 64;
  scene.height = 48;
  scene.focal_px = 60;
  scene.distance = 3.5;
  return scene;
}
TemplateFusionOptions EveryPixelOneThread() {
  TemplateFusionOptions options;
  options.point_stride_px = 1;
  options.num_threads = 1;
  return options;
}

TEST(FusionWorkspace, WritesFusedPlyAndMeshThatColmapReads) {
  const std::string dir = MakeTestDir("torus");
  testing::SceneOptions scene = TorusViews();
  scene.depth_noise = 0.003;
  const testing::Sdf sdf = testing::TorusSdf(1.0, 0.4);
  const std::vector<FusionView> views = testing::RenderViews(sdf, scene);
  WriteWorkspace(views, dir);

  TemplateFusionOptions options = EveryPixelOneThread();
  options.write_intermediate = true;
  StageTimings timings;
  const TemplateFusionResult result = RunTemplateFusion(dir, options, &timings);
  std::cerr << result.BriefReport() << "\n" << timings.Table() << "\n";
  EXPECT_EQ(result.num_views, static_cast<int>(views.size()));
  EXPECT_EQ(result.num_components, 1);
  EXPECT_EQ(result.euler_characteristic, 0);  // a torus
  for (const char* name : {"fused.ply", "fused.ply.vis", "meshed-hair.ply",
                           "meshed-coarse-template.ply", "meshed-refined-template.ply"}) {
    EXPECT_TRUE(ExistsFile(JoinPaths(dir, name))) << name;
  }

  // fused.ply: on the torus, with .vis indices in image_idx order (ids were reversed: the
  // view i is image_idx n-1-i), each point seen by a view where it agrees with that depth.
  const std::vector<FusedPoint> points = ReadFusedPly(result.fused_path);
  ASSERT_EQ(static_cast<int>(points.size()), result.num_fused_points);
  const int n = static_cast<int>(views.size());
  int num_pairs = 0, num_agree = 0;
  for (const FusedPoint& p : points) {
    EXPECT_LT(testing::SurfaceDistance(sdf, p.xyz.cast<double>()), 0.03);
    ASSERT_FALSE(p.visible_image_idxs.empty());
    for (uint32_t idx : p.visible_image_idxs) {
      ASSERT_LT(idx, static_cast<uint32_t>(n));
      const FusionView& view = views[n - 1 - idx];
      int col, row;
      double z;
      ++num_pairs;
      // Merged points are voxel averages (2 pixels): the average may fall on a silhouette
      // pixel, hence a fraction, not every pair.
      num_agree += view.Project(p.xyz.cast<double>(), &col, &row, &z) &&
                   std::abs(view.depth.At(row, col) - z) < 0.05 * z;
    }
  }
  EXPECT_GT(num_agree, 0.95 * num_pairs) << num_agree << " of " << num_pairs;

  // meshed-hair.ply: normals and colours per vertex, near the torus.
  const TriangleMesh mesh = ReadMeshPly(result.mesh_path);
  EXPECT_EQ(static_cast<int>(mesh.vertices.size()), result.final_num_vertices);
  EXPECT_EQ(mesh.normals.size(), mesh.vertices.size());
  EXPECT_EQ(mesh.colors.size(), mesh.vertices.size());
  double mean_error = 0;
  for (const Eigen::Vector3f& v : mesh.vertices) {
    mean_error += testing::SurfaceDistance(sdf, v.cast<double>());
  }
  mean_error /= mesh.vertices.size();
  EXPECT_LT(mean_error, 0.02);

  // colmap reads our fused.ply (with its .vis) and meshes it.
  const char* colmap = HAIRMVS_COLMAP_EXECUTABLE;
  if (!ExistsFile(colmap)) GTEST_SKIP() << "no colmap binary at " << colmap;
  const std::string colmap_mesh = JoinPaths(dir, "meshed-poisson.ply");
  const std::string log = JoinPaths(dir, "colmap.log");
  const std::string command = std::string("QT_QPA_PLATFORM=offscreen '") + colmap +
                              "' poisson_mesher --input_path " + result.fused_path +
                              " --output_path " + colmap_mesh +
                              " --PoissonMeshing.depth 6 --PoissonMeshing.trim 0"
                              " --PoissonMeshing.num_threads 1 > '" + log + "' 2>&1";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << ReadTextFile(log);
  const TriangleMesh colmap_result = ReadMeshPly(colmap_mesh);
  EXPECT_GT(colmap_result.vertices.size(), 100u);
  EXPECT_GT(colmap_result.faces.size(), 100u);
  std::filesystem::remove_all(dir);
}

// stereo/fusion.cfg, where it exists, says which views are fused, as for colmap stereo_fusion;
// their .vis indices stay the model's.
TEST(FusionWorkspace, FusionCfgSaysWhichViewsAreFused) {
  const std::string dir = MakeTestDir("fusion_cfg");
  const std::vector<FusionView> views =
      testing::RenderViews(testing::TorusSdf(1.0, 0.4), TorusViews());
  const int n = static_cast<int>(views.size());
  ASSERT_GE(n, 3);
  WriteWorkspace(views, dir);
  const std::string cfg = JoinPaths(dir, "stereo", "fusion.cfg");
  WriteFileAtomically(cfg, [&](std::ostream& out) {
    out << views[0].name << "\n" << views[1].name << "\n";
  });
  StageTimings timings;
  const TemplateFusionResult result = RunTemplateFusion(dir, EveryPixelOneThread(), &timings);
  EXPECT_EQ(result.num_views, 2);
  const std::vector<FusedPoint> points = ReadFusedPly(result.fused_path);
  ASSERT_FALSE(points.empty());
  for (const FusedPoint& p : points) {
    for (uint32_t idx : p.visible_image_idxs) {
      // Ids were reversed: view i is image_idx n-1-i.
      ASSERT_TRUE(idx == static_cast<uint32_t>(n - 1) || idx == static_cast<uint32_t>(n - 2))
          << idx;
    }
  }
  // A listed view without a depth map (its stereo job not finished) is left out, in a warning.
  WriteFileAtomically(cfg, [&](std::ostream& out) {
    out << views[0].name << "\n" << views[1].name << "\n" << views[2].name << "\n";
  });
  const Workspace workspace = Workspace::Read(dir);
  std::filesystem::remove(workspace.DepthMapPath(views[2].name, "geometric"));
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(RunTemplateFusion(dir, EveryPixelOneThread(), &timings).num_views, 2);
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("1 of the 3 views to fuse have no depth map and are left out: " +
                     views[2].name),
            std::string::npos)
      << log;
  // A name that is no image of the model is named with the file.
  WriteFileAtomically(cfg, [&](std::ostream& out) { out << "nowhere.png\n"; });
  const std::string message =
      testing_util::ErrorOf([&] { RunTemplateFusion(dir, EveryPixelOneThread(), &timings); });
  EXPECT_NE(message.find(cfg), std::string::npos) << message;
  EXPECT_NE(message.find("nowhere.png"), std::string::npos) << message;
  // One view listed: too few to fuse, said with the count of maps fused.
  WriteFileAtomically(cfg, [&](std::ostream& out) { out << views[0].name << "\n"; });
  const std::string one =
      testing_util::ErrorOf([&] { RunTemplateFusion(dir, EveryPixelOneThread(), &timings); });
  EXPECT_NE(one.find("depth maps (of the 1 fused, a point every"), std::string::npos) << one;
  // A folder in the file's place is an error, not a fusion of every view.
  std::filesystem::remove(cfg);
  CreateDirs(cfg);
  const std::string folder =
      testing_util::ErrorOf([&] { RunTemplateFusion(dir, EveryPixelOneThread(), &timings); });
  EXPECT_NE(folder.find("The fusion config " + cfg + " is a folder, not a file"),
            std::string::npos)
      << folder;
  std::filesystem::remove_all(dir);
}

// Depth maps without normal maps (another tool's, or normal maps deleted to save space):
// the normals of the fused points come from the depth maps, and the log says so per view.
TEST(FusionWorkspace, NormalsFromTheDepthMapsWhereNormalMapsAreMissing) {
  const std::string dir = MakeTestDir("no_normals");
  const testing::Sdf sdf = testing::TorusSdf(1.0, 0.4);
  WriteWorkspace(testing::RenderViews(sdf, TorusViews()), dir);
  std::filesystem::remove_all(JoinPaths(dir, "stereo", "normal_maps"));
  const TemplateFusionOptions options = EveryPixelOneThread();
  StageTimings timings;
  ::testing::internal::CaptureStderr();
  const TemplateFusionResult result = RunTemplateFusion(dir, options, &timings);
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("no normal map " + JoinPaths(dir, "stereo", "normal_maps")),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("normals from the depth map"), std::string::npos) << log;
  const std::vector<FusedPoint> points = ReadFusedPly(result.fused_path);
  ASSERT_GT(points.size(), 500u);
  // Each fused normal against the torus' own (the SDF's gradient at the point).
  std::vector<double> angles_deg;
  for (const FusedPoint& p : points) {
    const Eigen::Vector3d truth = testing::SdfGradient(sdf, p.xyz.cast<double>()).normalized();
    const double cosine = std::clamp(truth.dot(p.normal.cast<double>().normalized()), -1.0, 1.0);
    angles_deg.push_back(std::acos(cosine) * 180 / M_PI);
  }
  std::nth_element(angles_deg.begin(), angles_deg.begin() + angles_deg.size() / 2,
                   angles_deg.end());
  std::printf("median normal error %.2f deg over %zu points\n", angles_deg[angles_deg.size() / 2],
              angles_deg.size());
  EXPECT_LT(angles_deg[angles_deg.size() / 2], 3.0);  // measured 0.7 degrees
  std::filesystem::remove_all(dir);
}

TEST(FusionWorkspace, NoDepthMapsIsAnErrorNamingTheFolder) {
  const std::string dir = MakeTestDir("empty");
  testing::SceneOptions scene;
  scene.width = 16;
  scene.height = 12;
  scene.focal_px = 15;
  scene.num_azimuths = 2;
  scene.elevations_deg = {0};
  WriteWorkspace(testing::RenderViews(testing::SphereSdf(1.0), scene), dir);
  std::filesystem::remove_all(JoinPaths(dir, "stereo"));
  try {
    RunTemplateFusion(dir, TemplateFusionOptions(), nullptr);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("stereo"), std::string::npos) << e.what();
  }
  // A mistyped workspace path is refused as no workspace, and not made.
  const std::string typo = JoinPaths(dir, "typo", "dense");
  const std::string error =
      testing_util::ErrorOf([&] { RunTemplateFusion(typo, TemplateFusionOptions(), nullptr); });
  EXPECT_NE(error.find("Missing workspace folder: " + typo), std::string::npos) << error;
  EXPECT_FALSE(std::filesystem::exists(JoinPaths(dir, "typo")));
  std::filesystem::remove_all(dir);
}

// A depth map of another aspect ratio than its image (another view's or model's) is an error
// naming it, not a camera stretched one way; views without a .geometric map among views with
// one are fused from their first estimate, and the log names them.
TEST(FusionWorkspace, DepthMapsThatDoNotFitTheirViewAreNamed) {
  const std::string dir = MakeTestDir("misfit");
  WriteWorkspace(testing::RenderViews(testing::TorusSdf(1.0, 0.4), TorusViews()), dir);
  const Workspace workspace = Workspace::Read(dir);
  const std::string first = workspace.ImageNames()[0], second = workspace.ImageNames()[1];
  const std::string depth_path = workspace.DepthMapPath(first, "geometric");
  const FloatMap depth = ReadMat(depth_path);
  const std::string size = std::to_string(depth.Width()) + " x " + std::to_string(depth.Height());
  const std::string transposed =
      std::to_string(depth.Height()) + " x " + std::to_string(depth.Width());
  WriteMat(depth_path, FloatMap(depth.Height(), depth.Width(), 1, 1.0f));
  std::filesystem::remove(workspace.NormalMapPath(first, "geometric"));
  const std::string error =
      testing_util::ErrorOf([&] { RunTemplateFusion(dir, EveryPixelOneThread(), nullptr); });
  EXPECT_EQ(error, depth_path + " is " + transposed + ", another aspect ratio than its image's " +
                       size + ": a map of another view, or of another model");
  WriteMat(depth_path, depth);
  for (const std::string kind : {"depth_maps", "normal_maps"}) {
    std::filesystem::rename(JoinPaths(dir, "stereo", kind, second + ".geometric.bin"),
                            JoinPaths(dir, "stereo", kind, second + ".photometric.bin"));
  }
  ::testing::internal::CaptureStderr();
  RunTemplateFusion(dir, EveryPixelOneThread(), nullptr);
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("1 of " + std::to_string(workspace.ImageNames().size()) +
                     " views have no .geometric depth map: fused from their .photometric one"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("agreement): " + second + "\n"), std::string::npos) << log;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hairmvs
