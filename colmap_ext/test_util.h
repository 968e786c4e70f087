#pragma once
// Test helpers (header-only, used by colmap_ext's tests and tests/colmap_interop): a small
// synthetic sparse model of PINHOLE cameras looking at a plane, comparisons; with
// src/core/test_util.h's ErrorOf and MakeTestDir.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <random>
#include <string>

#include "colmap_ext/reconstruction.h"
#include "colmap_ext/workspace.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/test_util.h"  // ErrorOf, MakeTestDir

namespace hairmvs {
namespace testing_util {

struct PlaneModelOptions {
  int width = 64;
  int height = 48;
  double focal_px = 50.0;
  double plane_z_m = 5.0;                // world plane z = plane_z_m, cameras at z = 0
  std::vector<Eigen::Vector3d> centres;  // camera centres; default: 3 views along x
  int num_points = 40;
  unsigned seed = 7;
};

// PINHOLE cameras (one per image, so camera ids differ), identity rotations (looking along
// +z), points on the plane visible in every view, keypoints in the SfM convention.
inline Reconstruction MakePlaneModel(PlaneModelOptions options = PlaneModelOptions()) {
  if (options.centres.empty()) {
    options.centres = {{0, 0, 0}, {0.5, 0, 0}, {-0.5, 0, 0}};
  }
  Reconstruction r;
  const double cx = options.width / 2.0, cy = options.height / 2.0;
  const int num_views = static_cast<int>(options.centres.size());
  for (int i = 0; i < num_views; ++i) {
    Camera camera;
    camera.camera_id = static_cast<uint32_t>(i + 1);
    camera.model_id = 1;
    camera.width = options.width;
    camera.height = options.height;
    camera.params = {options.focal_px, options.focal_px, cx, cy};
    r.cameras[camera.camera_id] = camera;
    Image image;
    image.image_id = static_cast<uint32_t>(i + 1);
    image.camera_id = camera.camera_id;
    image.name = std::string(1, static_cast<char>('a' + i)) + ".png";
    image.cam_from_world_rotation = Eigen::Quaterniond::Identity();
    image.cam_from_world_translation = -options.centres[i];
    r.images[image.image_id] = image;
  }
  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int k = 0; k < options.num_points; ++k) {
    Point3D point;
    point.point3D_id = static_cast<uint64_t>(k + 1);
    point.xyz = Eigen::Vector3d(u(rng) * options.plane_z_m * cx / options.focal_px,
                                u(rng) * options.plane_z_m * cy / options.focal_px,
                                options.plane_z_m);
    point.rgb[0] = static_cast<uint8_t>(k);
    point.rgb[1] = 128;
    point.rgb[2] = static_cast<uint8_t>(255 - k);
    point.error = 0.25;
    for (auto& [id, image] : r.images) {
      const Eigen::Vector3d x = image.R() * point.xyz + image.t();
      Point2D p;
      p.xy = Eigen::Vector2d(options.focal_px * x.x() / x.z() + cx,
                             options.focal_px * x.y() / x.z() + cy);
      p.point3D_id = point.point3D_id;
      point.track.push_back({id, static_cast<uint32_t>(image.points2D.size())});
      image.points2D.push_back(p);
    }
    r.points3D[point.point3D_id] = point;
  }
  r.SortImageOrder();
  return r;
}

inline void ExpectModelsEqual(const Reconstruction& a, const Reconstruction& b,
                              double tolerance = 0.0) {
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (const auto& [id, ca] : a.cameras) {
    ASSERT_TRUE(b.cameras.count(id)) << "camera " << id;
    const Camera& cb = b.cameras.at(id);
    EXPECT_EQ(ca.model_id, cb.model_id);
    EXPECT_EQ(ca.width, cb.width);
    EXPECT_EQ(ca.height, cb.height);
    ASSERT_EQ(ca.params.size(), cb.params.size());
    for (size_t k = 0; k < ca.params.size(); ++k) {
      EXPECT_NEAR(ca.params[k], cb.params[k], tolerance);
    }
  }
  ASSERT_EQ(a.images.size(), b.images.size());
  for (const auto& [id, ia] : a.images) {
    ASSERT_TRUE(b.images.count(id)) << "image " << id;
    const Image& ib = b.images.at(id);
    EXPECT_EQ(ia.name, ib.name);
    EXPECT_EQ(ia.camera_id, ib.camera_id);
    EXPECT_LE((ia.cam_from_world_rotation.coeffs() - ib.cam_from_world_rotation.coeffs())
                  .cwiseAbs()
                  .maxCoeff(),
              tolerance);
    EXPECT_LE((ia.cam_from_world_translation - ib.cam_from_world_translation)
                  .cwiseAbs()
                  .maxCoeff(),
              tolerance);
    ASSERT_EQ(ia.points2D.size(), ib.points2D.size());
    for (size_t k = 0; k < ia.points2D.size(); ++k) {
      EXPECT_LE((ia.points2D[k].xy - ib.points2D[k].xy).cwiseAbs().maxCoeff(), tolerance);
      EXPECT_EQ(ia.points2D[k].point3D_id, ib.points2D[k].point3D_id);
    }
  }
  ASSERT_EQ(a.points3D.size(), b.points3D.size());
  for (const auto& [id, pa] : a.points3D) {
    ASSERT_TRUE(b.points3D.count(id)) << "point " << id;
    const Point3D& pb = b.points3D.at(id);
    EXPECT_LE((pa.xyz - pb.xyz).cwiseAbs().maxCoeff(), tolerance);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(pa.rgb[k], pb.rgb[k]);
    EXPECT_NEAR(pa.error, pb.error, tolerance);
    ASSERT_EQ(pa.track.size(), pb.track.size());
    for (size_t k = 0; k < pa.track.size(); ++k) {
      EXPECT_EQ(pa.track[k].image_id, pb.track[k].image_id);
      EXPECT_EQ(pa.track[k].point2D_idx, pb.track[k].point2D_idx);
    }
  }
}

// A dense workspace on disk: sparse/ (binary unless `text`), images/ (a textured grey
// picture per image, at the camera's size), stereo/.
inline void WriteTestWorkspace(const std::string& dir, const Reconstruction& model,
                               bool text = false) {
  WriteReconstruction(model, JoinPaths(dir, "sparse"),
                      text ? ModelFormat::kText : ModelFormat::kBinary);
  for (const auto& [id, image] : model.images) {
    const Camera& camera = model.cameras.at(image.camera_id);
    FloatMap picture(static_cast<int>(camera.width), static_cast<int>(camera.height), 1);
    for (int r = 0; r < picture.Height(); ++r) {
      for (int c = 0; c < picture.Width(); ++c) {
        picture.At(r, c) = static_cast<float>(((r * 7 + c * 13 + id * 29) % 64) / 63.0);
      }
    }
    WriteImage(JoinPaths(dir, "images", image.name), picture);
  }
  CreateDirs(JoinPaths(dir, "stereo", "depth_maps"));
  CreateDirs(JoinPaths(dir, "stereo", "normal_maps"));
}

}  // namespace testing_util
}  // namespace hairmvs
