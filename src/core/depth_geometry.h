#pragma once
// Geometry of z-depth maps on the SfM pixel grid: pixel (col, row) is centred at image point
// (col + 0.5, row + 0.5) (the convention of the ground truth and of hairmvs; COLMAP's dense
// code uses (col, row), half a pixel off).

#include <Eigen/Core>
#include <string>

#include "src/core/float_map.h"

namespace hairmvs {

// The camera-frame point seen at pixel (col, row) with z-depth `depth`:
// depth * K^-1 * (col + 0.5, row + 0.5, 1).
Eigen::Vector3d BackProjectPixel(const Eigen::Matrix3d& K, double col, double row, double depth);

// The world point that the camera X_cam = R X_world + t sees at pixel (col, row) with z-depth
// `depth`: R^T (BackProjectPixel(K, col, row, depth) - t).
Eigen::Vector3d BackProjectPixelToWorld(const Eigen::Matrix3d& K, const Eigen::Matrix3d& R,
                                        const Eigen::Vector3d& t, double col, double row,
                                        double depth);

// The pixel of a width x height grid that a world point lands in, seen by the camera
// X_cam = R X_world + t (pixel (col, row) covers [col, col + 1) x [row, row + 1)), and its
// z-depth; false when it is behind the camera or off the grid.
bool ProjectToPixel(const Eigen::Matrix3d& K, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                    int width, int height, const Eigen::Vector3d& world, int* col, int* row,
                    double* depth);

// The focal length in px that the depth-continuity rule below (ContinuesSurface's slope)
// takes: the mean of K's two.
inline double MeanFocalPx(const Eigen::Matrix3d& K) { return 0.5 * (K(0, 0) + K(1, 1)); }

// The z-depth of a map at image point (x, y) (pixel (col, row) centred at (col + 0.5,
// row + 0.5)): bilinear between the four pixel centres around (x, y) where all four have a
// depth and continue one surface (each pair of neighbours within max_slope * depth / focal,
// the lowest of the four's depth: NormalMapFromDepthMap's rule), else the depth of the pixel
// (x, y) lies in, so that a silhouette or a step between layers is not blended. A point half a
// pixel off a centre on a slanted surface then reads the surface's depth there, not its
// neighbour's. 0 off the map or where that pixel has no depth.
double SampleDepthMap(const FloatMap& depth, double x, double y, double focal,
                      double max_slope = 10.0);

// Where the line of sight through a world point meets the depth map `depth` of the camera
// X_cam = R X_world + t: the map's depth at the point's exact image position (SampleDepthMap,
// focal the mean of K's two), and the point's own z-depth. False behind the camera, off the
// map or where the map has no depth there. A map of part of the image has its pixel (0, 0) at
// the image's (col0, row0).
bool MapDepthOnRay(const Eigen::Matrix3d& K, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                   const FloatMap& depth, const Eigen::Vector3d& world, double* z,
                   double* map_depth, int col0 = 0, int row0 = 0);

// Whether a w x h picture is one of width x height at another scale, to a pixel's rounding each
// way: a depth map or mask that a max_image_size made smaller, not one of another aspect ratio.
bool IsScaledCopy(int w, int h, int width, int height);

// Whether `max_image_size` is one COLMAP takes: > 0, or -1 for none (colmap aborts on 0). Each
// command words its own error.
inline bool IsValidMaxImageSize(int max_image_size) {
  return max_image_size > 0 || max_image_size == -1;
}

// A pinhole camera on a width x height pixel grid: X_cam = R X_world + t. The stereo's cameras
// at the processing resolution and its pyramid levels, the evaluators' workspace and true
// cameras (ViewCamera in colmap_ext/workspace.h builds a view's).
struct StereoCamera {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  int width = 0;
  int height = 0;

  Eigen::Vector3d Center() const { return -R.transpose() * t; }
  // The same camera for an image of width x height covering the same extent (a resized image).
  StereoCamera Scaled(int new_width, int new_height) const;
  // Scaled to a map of map_width x map_height read from `map_path` (COLMAP writes smaller maps
  // with --PatchMatchStereo.max_image_size); throws naming the file when the map is not the
  // image at another scale (IsScaledCopy), e.g. a map of another view or model.
  StereoCamera ScaledToMap(int map_width, int map_height, const std::string& map_path) const;
  // Scaled to COLMAP's max_image_size rule: the longer side at most `max_image_size` (scale,
  // round); itself when max_image_size <= 0 or the image is no larger.
  StereoCamera AtMaxImageSize(int max_image_size) const;
  // The camera of level `level` of the 2 x 2 box pyramid (DownsampleHalf in
  // src/orientation/orientation_field.h): image coordinates halve exactly at every level and the
  // size is ceil(size / 2^level). Not Scaled(ceil(W / 2^level), ...): for an odd size the last
  // pixel of a level reaches beyond the image, so the level does not cover the same extent.
  StereoCamera PyramidLevel(int level) const;
  // The world point seen at pixel (col, row) with z-depth `depth`.
  Eigen::Vector3d BackProject(int col, int row, double depth) const;
  // The pixel a world point lands in and its z-depth; false when it is behind the camera or
  // off the grid.
  bool Project(const Eigen::Vector3d& world, int* col, int* row, double* depth) const;
};

// Camera-frame unit normals (3 channels: x, y, z) of the surface of a z-depth map, from
// central differences of the back-projected neighbours (one-sided where one neighbour is
// missing or across a discontinuity), oriented towards the camera (n . X < 0); 0 exactly where
// the depth is invalid (<= 0), as in COLMAP's maps, whose fusion drops a depth without a normal.
// Where one image direction has no usable neighbour (a strand one pixel wide), the normal is
// the one across the other direction's tangent that faces the camera most; where neither has
// (an isolated depth), the line of sight reversed. Two neighbours are discontinuous when their
// depths differ by more than max_slope * depth / focal, i.e. the surface would be steeper than
// atan(max_slope) from fronto-parallel (default ~84 degrees).
FloatMap NormalMapFromDepthMap(const FloatMap& depth, const Eigen::Matrix3d& K,
                               double max_slope = 10.0);
// Whether the depth at (row, col) (> 0) continues its surface (NormalMapFromDepthMap's rule)
// to a neighbour along its row and to one along its column: where the normal is the surface's
// own, not a fallback across a strand or along the line of sight.
bool HasSurfaceNeighboursBothWays(const FloatMap& depth, int row, int col, double focal,
                                  double max_slope = 10.0);

}  // namespace hairmvs
