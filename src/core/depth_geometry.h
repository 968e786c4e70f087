#pragma once
// Geometry of z-depth maps on the SfM pixel grid: pixel (col, row) is centred at image point
// (col + 0.5, row + 0.5) (the convention of the ground truth and of hairmvs; COLMAP's dense
// code uses (col, row), half a pixel off).

#include <Eigen/Core>

#include "src/core/float_map.h"

namespace hairmvs {

// The camera-frame point seen at pixel (col, row) with z-depth `depth`:
// depth * K^-1 * (col + 0.5, row + 0.5, 1).
Eigen::Vector3d BackProjectPixel(const Eigen::Matrix3d& K, double col, double row, double depth);

// Camera-frame unit normals (3 channels: x, y, z) of the surface of a z-depth map, from
// central differences of the back-projected neighbours (one-sided where one neighbour is
// missing or across a discontinuity), oriented towards the camera (n . X < 0). 0 where the
// depth is invalid (<= 0) or where a direction has no usable neighbour. Two neighbours are
// discontinuous when their depths differ by more than max_slope * depth / focal, i.e. the
// surface would be steeper than atan(max_slope) from fronto-parallel (default ~84 degrees).
FloatMap NormalMapFromDepthMap(const FloatMap& depth, const Eigen::Matrix3d& K,
                               double max_slope = 10.0);

}  // namespace hairmvs
