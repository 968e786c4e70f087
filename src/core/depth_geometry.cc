#include "src/core/depth_geometry.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "src/core/logging.h"

namespace hairmvs {

Eigen::Vector3d BackProjectPixel(const Eigen::Matrix3d& K, double col, double row, double depth) {
  // Solve K * (x, y, 1) = (u, v, 1) for an upper-triangular K (skew allowed).
  const double v = row + 0.5;
  const double u = col + 0.5;
  const double y = (v - K(1, 2)) / K(1, 1);
  const double x = (u - K(0, 2) - K(0, 1) * y) / K(0, 0);
  return Eigen::Vector3d(x * depth, y * depth, depth);
}

StereoCamera StereoCamera::Scaled(int new_width, int new_height) const {
  StereoCamera scaled = *this;
  const double sx = static_cast<double>(new_width) / width;
  const double sy = static_cast<double>(new_height) / height;
  // Continuous image coordinates scale exactly in the SfM convention (the image spans [0, W]).
  scaled.K.row(0) *= sx;
  scaled.K.row(1) *= sy;
  scaled.width = new_width;
  scaled.height = new_height;
  return scaled;
}

bool IsScaledCopy(int w, int h, int width, int height) {
  if (w == width && h == height) return true;
  if (w <= 0 || h <= 0 || width <= 0 || height <= 0) return false;
  // Whether b's size is a's scaled, to a pixel in b's units (one side rounded either way).
  auto fits = [](double a_w, double a_h, double b_w, double b_h) {
    return std::abs(a_h * b_w / a_w - b_h) <= 1 || std::abs(a_w * b_h / a_h - b_w) <= 1;
  };
  return fits(w, h, width, height) || fits(width, height, w, h);
}

StereoCamera StereoCamera::ScaledToMap(int map_width, int map_height,
                                       const std::string& map_path) const {
  THROW_IF(!IsScaledCopy(map_width, map_height, width, height),
           map_path << " is " << map_width << " x " << map_height
                    << ", another aspect ratio than its image's " << width << " x " << height
                    << ": a map of another view, or of another model");
  return Scaled(map_width, map_height);
}

StereoCamera StereoCamera::AtMaxImageSize(int max_image_size) const {
  if (max_image_size <= 0 || std::max(width, height) <= max_image_size) return *this;
  const double scale = static_cast<double>(max_image_size) / std::max(width, height);
  return Scaled(std::max(1, static_cast<int>(std::lround(width * scale))),
                std::max(1, static_cast<int>(std::lround(height * scale))));
}

StereoCamera StereoCamera::PyramidLevel(int level) const {
  CHECK_GE(level, 0);
  StereoCamera scaled = *this;
  for (int l = 0; l < level; ++l) {
    scaled.K.row(0) *= 0.5;
    scaled.K.row(1) *= 0.5;
    scaled.width = (scaled.width + 1) / 2;
    scaled.height = (scaled.height + 1) / 2;
  }
  return scaled;
}

namespace {

// Whether neighbouring depths `a` and `b` (> 0), a pixel apart, lie on one surface: no steeper
// than atan(max_slope) from fronto-parallel at `depth` seen with `focal` px.
bool ContinuesSurface(double a, double b, double depth, double focal, double max_slope) {
  return std::abs(a - b) <= max_slope * depth / focal;
}

// Whether the depth d at (r, c) continues its surface to its neighbour one step (dr, dc) ahead
// and one step behind.
void SurfaceNeighbours(const FloatMap& depth, int r, int c, double d, int dr, int dc,
                       double focal, double max_slope, bool* ahead, bool* behind) {
  const auto continues = [&](int nr, int nc) {
    if (nr < 0 || nr >= depth.Height() || nc < 0 || nc >= depth.Width()) return false;
    const double n = depth.At(nr, nc);
    return n > 0 && ContinuesSurface(n, d, d, focal, max_slope);
  };
  *ahead = continues(r + dr, c + dc);
  *behind = continues(r - dr, c - dc);
}

}  // namespace

bool HasSurfaceNeighboursBothWays(const FloatMap& depth, int row, int col, double focal,
                                  double max_slope) {
  const double d = depth.At(row, col);
  if (!(d > 0)) return false;
  bool right, left, below, above;
  SurfaceNeighbours(depth, row, col, d, 0, 1, focal, max_slope, &right, &left);
  SurfaceNeighbours(depth, row, col, d, 1, 0, focal, max_slope, &below, &above);
  return (right || left) && (below || above);
}

double SampleDepthMap(const FloatMap& depth, double x, double y, double focal,
                      double max_slope) {
  CHECK_EQ(depth.Channels(), 1);
  if (!(x >= 0 && y >= 0 && x < depth.Width() && y < depth.Height())) return 0.0;
  const double nearest = depth.At(static_cast<int>(y), static_cast<int>(x));
  if (!(nearest > 0)) return 0.0;
  // The four centres around (x, y): columns c0, c0 + 1 and rows r0, r0 + 1.
  const double u = x - 0.5, v = y - 0.5;
  const int c0 = static_cast<int>(std::floor(u)), r0 = static_cast<int>(std::floor(v));
  if (c0 < 0 || r0 < 0 || c0 + 1 >= depth.Width() || r0 + 1 >= depth.Height()) return nearest;
  const double d00 = depth.At(r0, c0), d01 = depth.At(r0, c0 + 1);
  const double d10 = depth.At(r0 + 1, c0), d11 = depth.At(r0 + 1, c0 + 1);
  const double lowest = std::min({d00, d01, d10, d11});
  if (!(lowest > 0)) return nearest;
  const auto continues = [&](double a, double b) {
    return ContinuesSurface(a, b, lowest, focal, max_slope);
  };
  const bool one_surface = continues(d00, d01) && continues(d10, d11) &&
                           continues(d00, d10) && continues(d01, d11);
  if (!one_surface) return nearest;
  const double a = u - c0, b = v - r0;
  return (1 - b) * ((1 - a) * d00 + a * d01) + b * ((1 - a) * d10 + a * d11);
}

bool MapDepthOnRay(const Eigen::Matrix3d& K, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                   const FloatMap& depth, const Eigen::Vector3d& world, double* z,
                   double* map_depth, int col0, int row0) {
  const Eigen::Vector3d x = K * (R * world + t);
  if (!(x.z() > 0)) return false;
  *z = x.z();
  // Exact where the point falls on the map: x - col0 lies in [0, x] and keeps x's fraction.
  *map_depth =
      SampleDepthMap(depth, x.x() / x.z() - col0, x.y() / x.z() - row0, MeanFocalPx(K));
  return *map_depth > 0;
}

Eigen::Vector3d BackProjectPixelToWorld(const Eigen::Matrix3d& K, const Eigen::Matrix3d& R,
                                        const Eigen::Vector3d& t, double col, double row,
                                        double depth) {
  return R.transpose() * (BackProjectPixel(K, col, row, depth) - t);
}

bool ProjectToPixel(const Eigen::Matrix3d& K, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                    int width, int height, const Eigen::Vector3d& world, int* col, int* row,
                    double* depth) {
  const Eigen::Vector3d x = K * (R * world + t);
  if (!(x.z() > 0)) return false;
  const double c = std::floor(x.x() / x.z()), r = std::floor(x.y() / x.z());
  if (!(c >= 0 && r >= 0 && c < width && r < height)) return false;
  *col = static_cast<int>(c);
  *row = static_cast<int>(r);
  *depth = x.z();
  return true;
}

Eigen::Vector3d StereoCamera::BackProject(int col, int row, double depth) const {
  return BackProjectPixelToWorld(K, R, t, col, row, depth);
}

bool StereoCamera::Project(const Eigen::Vector3d& world, int* col, int* row,
                           double* depth) const {
  return ProjectToPixel(K, R, t, width, height, world, col, row, depth);
}

FloatMap NormalMapFromDepthMap(const FloatMap& depth, const Eigen::Matrix3d& K,
                               double max_slope) {
  CHECK_EQ(depth.Channels(), 1);
  const int width = depth.Width();
  const int height = depth.Height();
  FloatMap normals(width, height, 3, 0.0f);
  const double focal = MeanFocalPx(K);
  // Tangent along one image direction (dr, dc) at (r, c): central difference when both
  // neighbours continue the surface, one-sided when only one does, none otherwise.
  auto tangent = [&](int r, int c, double d, int dr, int dc, Eigen::Vector3d* t) {
    bool plus_ok, minus_ok;
    SurfaceNeighbours(depth, r, c, d, dr, dc, focal, max_slope, &plus_ok, &minus_ok);
    if (!plus_ok && !minus_ok) return false;
    const Eigen::Vector3d p_plus =
        plus_ok ? BackProjectPixel(K, c + dc, r + dr, depth.At(r + dr, c + dc))
                : BackProjectPixel(K, c, r, d);
    const Eigen::Vector3d p_minus =
        minus_ok ? BackProjectPixel(K, c - dc, r - dr, depth.At(r - dr, c - dc))
                 : BackProjectPixel(K, c, r, d);
    *t = p_plus - p_minus;
    return true;
  };
#pragma omp parallel for schedule(static)
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const double d = depth.At(r, c);
      if (!(d > 0)) continue;
      const Eigen::Vector3d ray = BackProjectPixel(K, c, r, d).normalized();
      Eigen::Vector3d t_col, t_row;
      const bool has_col = tangent(r, c, d, 0, 1, &t_col);
      const bool has_row = tangent(r, c, d, 1, 0, &t_row);
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      if (has_col && has_row) {
        n = t_col.cross(t_row);
      } else if (has_col || has_row) {
        // One tangent (a strand one pixel wide): the normal across it that faces the camera
        // most, as a strand's does where the viewer sees it.
        const Eigen::Vector3d along = (has_col ? t_col : t_row).normalized();
        n = along.dot(ray) * along - ray;
      }
      const double norm = n.norm();
      // No tangent, or degenerate ones: the line of sight reversed.
      n = norm > 1e-9 ? Eigen::Vector3d(n / norm) : Eigen::Vector3d(-ray);
      if (n.dot(ray) > 0) n = -n;
      for (int k = 0; k < 3; ++k) normals.At(r, c, k) = static_cast<float>(n(k));
    }
  }
  return normals;
}

}  // namespace hairmvs
