#pragma once
// The in-memory inputs and outputs of template fusion, free of any file format, so that tests
// can hand the pipeline synthetic depth maps directly.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "src/core/depth_geometry.h"
#include "src/core/float_map.h"
#include "src/core/logging.h"

namespace hairmvs {

// One depth map with its calibrated pinhole camera (cam_from_world: X_cam = R X + t).
struct FusionView {
  std::string name;
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  FloatMap depth;   // z-depth on the pixel grid, 0 = invalid
  // 3 channels, camera-frame unit normals facing the camera; FuseViews needs them
  // (RunTemplateFusion computes them from the depth where the workspace has no normal map).
  FloatMap normal;
  FloatMap rgb;     // 3 channels (R, G, B) in [0, 1]; empty = grey
  // The maps may hold only the box of the whole map where it has depths (CropToDepth): hair
  // fills a fifth of a view, and a workspace's maps are held at once. Their pixel (0, 0) is the
  // whole map's (col0, row0), of whole_width x whole_height pixels (0: never cropped), and K is
  // the whole map's (the image's, or the camera scaled to a smaller map). The methods below
  // take and give the maps' pixels.
  int col0 = 0, row0 = 0;
  int whole_width = 0, whole_height = 0;

  // Crops depth and the normal and rgb maps that are not empty (each of the depth map's size)
  // to the box of the depth map's depths (nothing if it has none). Every method reads outside
  // the box as no depth, as it read the values not above 0 there, and at the same positions
  // of the whole map: the results are the same, bit for bit.
  void CropToDepth() {
    for (const FloatMap* map : {&normal, &rgb}) {
      CHECK(map->Empty() || (map->Width() == depth.Width() && map->Height() == depth.Height()))
          << name << ": maps of " << map->Width() << " x " << map->Height() << " and "
          << depth.Width() << " x " << depth.Height() << " px";
    }
    if (whole_width == 0) {
      whole_width = depth.Width();
      whole_height = depth.Height();
    }
    const PixelBox box = BoundingBoxAbove(depth, 0.0f);
    if (box.Empty()) return;
    for (FloatMap* map : {&depth, &normal, &rgb}) {
      if (!map->Empty()) *map = CropFloatMap(*map, box.x0, box.y0, box.width, box.height);
    }
    col0 += box.x0;
    row0 += box.y0;
  }
  // `part`, a map of the maps' box (e.g. a depth map filtered here), held as such.
  CroppedFloatMap Part(FloatMap part) const {
    return {std::move(part), PixelBox{col0, row0, depth.Width(), depth.Height()},
            whole_width == 0 ? depth.Width() : whole_width,
            whole_height == 0 ? depth.Height() : whole_height};
  }
  // `part` in a whole map of zeros (values not above 0 outside the box come back as +0).
  FloatMap Whole(const FloatMap& part) const { return Part(part).Whole(); }

  Eigen::Vector3d Center() const { return -R.transpose() * t; }
  // Projects a world point into the pixel grid (SfM convention: pixel (col,row) covers
  // [col, col+1) x [row, row+1)). Returns false behind the camera or outside the map.
  bool Project(const Eigen::Vector3d& world, int* col, int* row, double* z) const {
    int image_col, image_row;
    double depth_z;
    if (!ProjectToPixel(K, R, t, col0 + depth.Width(), row0 + depth.Height(), world,
                        &image_col, &image_row, &depth_z) ||
        image_col < col0 || image_row < row0) {
      return false;
    }
    *col = image_col - col0;
    *row = image_row - row0;
    *z = depth_z;
    return true;
  }
  // The world point this map's camera sees at pixel (col, row) with z-depth `z`.
  Eigen::Vector3d BackProject(int col, int row, double z) const {
    return BackProjectPixelToWorld(K, R, t, col + col0, row + row0, z);
  }
  // The centre of pixel (col, row) in the whole map's image coordinates (SfM convention).
  Eigen::Vector2d PixelCentre(int col, int row) const {
    return Eigen::Vector2d(col + col0 + 0.5, row + row0 + 0.5);
  }
  // The point of this map's surface on the line of sight through `world`, whose own z-depth
  // is `z`, given the map's depth there: how the map "sees" that point.
  Eigen::Vector3d SurfaceOnRay(const Eigen::Vector3d& world, double z, double map_depth) const {
    const Eigen::Vector3d c = Center();
    return c + (world - c) * (map_depth / z);
  }
  // The map's depth where the line of sight through `world` meets it (SampleDepthMap at the
  // point's exact image position) and the point's own z-depth: false behind the camera, off
  // the map or where the map has no depth there.
  bool DepthOnRay(const Eigen::Vector3d& world, double* z, double* map_depth) const {
    return MapDepthOnRay(K, R, t, depth, world, z, map_depth, col0, row0);
  }
  Eigen::Vector3d WorldNormalAt(int row, int col) const {
    const Eigen::Vector3d n_cam(normal.At(row, col, 0), normal.At(row, col, 1),
                                normal.At(row, col, 2));
    return R.transpose() * n_cam;
  }
};

// A triangle mesh in double precision while it is being shaped.
struct FusionMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;
  std::vector<Eigen::Vector3d> normals;  // per vertex, area-weighted, unit
  std::vector<std::array<uint8_t, 3>> colors;

  void ComputeVertexNormals();
  double MeanEdgeLength() const;
  // Each edge once, however many faces share it, as (lower index, higher index), ascending.
  std::vector<std::pair<int, int>> Edges() const;
  int NumEdges() const;
  int EulerCharacteristic() const;  // V - E + F
  // Face indices per connected component (faces sharing a vertex are connected).
  std::vector<int> FaceComponents(int* num_components) const;
  // Keeps the faces with keep[f], then drops unreferenced vertices.
  void KeepFaces(const std::vector<bool>& keep);
};

// fused.ply's points before they are written.
struct FusionPoints {
  std::vector<Eigen::Vector3f> xyz;
  std::vector<Eigen::Vector3f> normal;
  std::vector<std::array<uint8_t, 3>> rgb;
  std::vector<std::vector<uint32_t>> visible_views;  // indices into the views, ascending
  size_t Size() const { return xyz.size(); }
};

}  // namespace hairmvs
