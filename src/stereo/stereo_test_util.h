#pragma once
// Test scenes for stereo (header-only, used by tests): pinhole cameras around a plane or a
// sphere covered in thin bright strands of varied orientation; per view the rendered grey
// image, its orientation field (analytic: the projected strand directions), and the true
// z-depth of the surface.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include "src/core/float_map.h"
#include "src/fusion/fusion_view.h"
#include "src/stereo/stereo_geometry.h"

namespace hairmvs {
namespace testing_util {

// A camera at `center` looking at `target`, rolled by `roll_rad` about its optical axis.
inline StereoCamera LookAtCamera(const Eigen::Vector3d& center, const Eigen::Vector3d& target,
                                 double focal_px, int width, int height, double roll_rad = 0) {
  const Eigen::Vector3d z = (target - center).normalized();
  Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z);  // world +y is image down
  if (x.norm() < 1e-6) x = Eigen::Vector3d::UnitX();
  x.normalize();
  x = -x;
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R;
  R.row(0) = x.transpose();
  R.row(1) = y.transpose();
  R.row(2) = z.transpose();
  const Eigen::Matrix3d roll =
      Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  StereoCamera camera;
  camera.R = roll * R;
  camera.t = -camera.R * center;
  camera.K << focal_px, 0, width / 2.0, 0, focal_px, height / 2.0, 0, 0, 1;
  camera.width = width;
  camera.height = height;
  return camera;
}

// A plane through `point` with normal `normal`, or a sphere (centre, radius).
struct Surface {
  bool sphere = false;
  Eigen::Vector3d point = Eigen::Vector3d(0, 0, 1);
  Eigen::Vector3d normal = Eigen::Vector3d(0, 0, -1);
  double radius = 0.3;

  // First hit along the ray from `origin` in direction `dir` (unit); -1 if none.
  double Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) const {
    if (!sphere) {
      const double denom = normal.dot(dir);
      if (std::abs(denom) < 1e-12) return -1;
      const double s = normal.dot(point - origin) / denom;
      return s > 0 ? s : -1;
    }
    const Eigen::Vector3d oc = origin - point;
    const double b = oc.dot(dir);
    const double c = oc.squaredNorm() - radius * radius;
    const double disc = b * b - c;
    if (disc < 0) return -1;
    const double s = -b - std::sqrt(disc);
    return s > 0 ? s : -1;
  }
  Eigen::Vector3d NormalAt(const Eigen::Vector3d& x) const {
    return sphere ? (x - point).normalized() : normal.normalized();
  }
};

// Strands: polylines on the surface, random start, direction and slight curvature.
inline std::vector<std::vector<Eigen::Vector3d>> MakeStrands(const Surface& surface,
                                                             int num_strands, double extent_m,
                                                             double length_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::vector<std::vector<Eigen::Vector3d>> strands;
  const Eigen::Vector3d n = surface.normal.normalized();
  Eigen::Vector3d e1 = n.cross(Eigen::Vector3d::UnitY());
  if (e1.norm() < 1e-6) e1 = n.cross(Eigen::Vector3d::UnitX());
  e1.normalize();
  const Eigen::Vector3d e2 = n.cross(e1);
  for (int s = 0; s < num_strands; ++s) {
    const double angle = M_PI * uni(rng);
    const double curvature = 3.0 * uni(rng);  // radians per metre
    Eigen::Vector3d x;
    if (surface.sphere) {
      // A point on the cap facing -z (towards the cameras).
      Eigen::Vector3d d(extent_m * uni(rng), extent_m * uni(rng), -1.0);
      x = surface.point + surface.radius * d.normalized();
    } else {
      x = surface.point + extent_m * (uni(rng) * e1 + uni(rng) * e2);
    }
    Eigen::Vector3d normal = surface.NormalAt(x);
    Eigen::Vector3d a = normal.cross(Eigen::Vector3d::UnitY());
    if (a.norm() < 1e-6) a = normal.cross(Eigen::Vector3d::UnitX());
    a.normalize();
    const Eigen::Vector3d b = normal.cross(a);
    Eigen::Vector3d dir = std::cos(angle) * a + std::sin(angle) * b;
    std::vector<Eigen::Vector3d> strand = {x};
    const int steps = 24;
    const double ds = length_m / steps;
    for (int i = 0; i < steps; ++i) {
      x = x + ds * dir;
      if (surface.sphere) x = surface.point + surface.radius * (x - surface.point).normalized();
      normal = surface.NormalAt(x);
      // Turn slightly within the tangent plane.
      dir = Eigen::AngleAxisd(curvature * ds, normal) * (dir - dir.dot(normal) * normal);
      dir.normalize();
      strand.push_back(x);
    }
    strands.push_back(strand);
  }
  return strands;
}

struct RenderedView {
  StereoCamera camera;
  FloatMap gray;         // bright strands on black, in [0, 1]
  FloatMap orientation;  // 2 channels: sum of w exp(2 i theta) of the strands at the pixel
  FloatMap depth;        // true z-depth of the surface, 0 where missed
};

inline RenderedView RenderView(const StereoCamera& camera, const Surface& surface,
                               const std::vector<std::vector<Eigen::Vector3d>>& strands) {
  const int w = camera.width, h = camera.height;
  RenderedView view;
  view.camera = camera;
  view.gray = FloatMap(w, h, 1);
  view.orientation = FloatMap(w, h, 2);
  view.depth = FloatMap(w, h, 1);
  const Eigen::Vector3d center = camera.Center();
  const Eigen::Matrix3d K_inv = camera.K.inverse();
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const Eigen::Vector3d ray_cam = K_inv * Eigen::Vector3d(col + 0.5, row + 0.5, 1.0);
      const Eigen::Vector3d dir = (camera.R.transpose() * ray_cam).normalized();
      const double s = surface.Intersect(center, dir);
      if (s > 0) view.depth.At(row, col) = static_cast<float>((camera.R * (s * dir)).z());
    }
  }
  auto project = [&](const Eigen::Vector3d& x, Eigen::Vector2d* u) {
    const Eigen::Vector3d c = camera.K * (camera.R * x + camera.t);
    if (c.z() <= 0) return false;
    *u = Eigen::Vector2d(c.x() / c.z(), c.y() / c.z());
    return true;
  };
  std::vector<std::complex<double>> o(static_cast<size_t>(w) * h, 0.0);
  std::vector<double> intensity(static_cast<size_t>(w) * h, 0.0);
  for (const auto& strand : strands) {
    for (size_t i = 0; i + 1 < strand.size(); ++i) {
      const Eigen::Vector3d mid = 0.5 * (strand[i] + strand[i + 1]);
      if ((center - mid).dot(surface.NormalAt(mid)) <= 0) continue;  // back-facing
      Eigen::Vector2d a, b;
      if (!project(strand[i], &a) || !project(strand[i + 1], &b)) continue;
      const Eigen::Vector2d d = b - a;
      const double len = d.norm();
      if (len < 1e-9) continue;
      const std::complex<double> phase = std::polar(1.0, 2.0 * std::atan2(d.y(), d.x()));
      const int c0 = std::max(0, static_cast<int>(std::floor(std::min(a.x(), b.x()) - 2)));
      const int c1 = std::min(w - 1, static_cast<int>(std::ceil(std::max(a.x(), b.x()) + 2)));
      const int r0 = std::max(0, static_cast<int>(std::floor(std::min(a.y(), b.y()) - 2)));
      const int r1 = std::min(h - 1, static_cast<int>(std::ceil(std::max(a.y(), b.y()) + 2)));
      for (int row = r0; row <= r1; ++row) {
        for (int col = c0; col <= c1; ++col) {
          const Eigen::Vector2d p(col + 0.5, row + 0.5);
          const double t = std::clamp((p - a).dot(d) / (len * len), 0.0, 1.0);
          const double dist = (a + t * d - p).norm();
          const double weight = std::max(0.0, 1.0 - dist / 0.8);
          if (weight <= 0) continue;
          const size_t k = static_cast<size_t>(row) * w + col;
          // Only where this segment is the visible surface (the sphere's far side is culled
          // above; strands lie on the surface, so no other occlusion).
          o[k] += weight * phase;
          intensity[k] = std::max(intensity[k], weight);
        }
      }
    }
  }
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const size_t k = static_cast<size_t>(row) * w + col;
      // Confidence saturates like F = response^gamma: unit magnitude where a strand is.
      const double mag = std::abs(o[k]);
      const std::complex<double> unit = mag > 1e-9 ? o[k] / mag : 0.0;
      const std::complex<double> value = unit * std::sqrt(std::min(mag, 1.0));
      view.orientation.At(row, col, 0) = static_cast<float>(value.real());
      view.orientation.At(row, col, 1) = static_cast<float>(value.imag());
      view.gray.At(row, col) = static_cast<float>(std::min(1.0, intensity[k]));
    }
  }
  return view;
}

// 2x2 box average to ((W + 1) / 2, (H + 1) / 2), every channel.
inline FloatMap Downsample2x2(const FloatMap& in) {
  FloatMap out((in.Width() + 1) / 2, (in.Height() + 1) / 2, in.Channels());
  for (int c = 0; c < in.Channels(); ++c) {
    for (int row = 0; row < out.Height(); ++row) {
      for (int col = 0; col < out.Width(); ++col) {
        double sum = 0;
        int n = 0;
        for (int r = 2 * row; r < std::min(2 * row + 2, in.Height()); ++r) {
          for (int q = 2 * col; q < std::min(2 * col + 2, in.Width()); ++q) {
            sum += in.At(r, q, c);
            ++n;
          }
        }
        out.At(row, col, c) = static_cast<float>(sum / n);
      }
    }
  }
  return out;
}

inline std::vector<FloatMap> Pyramid(const FloatMap& level0, int num_levels) {
  std::vector<FloatMap> levels = {level0};
  while (static_cast<int>(levels.size()) < num_levels) {
    levels.push_back(Downsample2x2(levels.back()));
  }
  return levels;
}

inline FloatMap RandomMap(int width, int height, int channels, unsigned seed, float lo = -1,
                          float hi = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uni(lo, hi);
  FloatMap map(width, height, channels);
  for (float& v : map.Data()) v = uni(rng);
  return map;
}

// A camera at `center` looking at the origin along +z-ish (no roll), and the exact z-depth map
// of the world plane z_world = 1 seen by it (all cameras sit at z_world = 0 and look up +z).
inline FusionView PlaneView(const Eigen::Vector3d& center, double yaw_rad) {
  FusionView view;
  view.K << 100, 0, 40, 0, 100, 30, 0, 0, 1;
  view.R = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitY()).toRotationMatrix().transpose();
  view.t = -view.R * center;
  view.depth = FloatMap(80, 60, 1, 0.0f);
  const Eigen::Matrix3d K_inv = view.K.inverse();
  for (int row = 0; row < 60; ++row) {
    for (int col = 0; col < 80; ++col) {
      // Ray in world coordinates; intersect z_world = 1.
      const Eigen::Vector3d ray_cam = K_inv * Eigen::Vector3d(col + 0.5, row + 0.5, 1.0);
      const Eigen::Vector3d ray = view.R.transpose() * ray_cam;
      const double s = (1.0 - center.z()) / ray.z();
      view.depth.At(row, col) = static_cast<float>(s * ray_cam.z());
    }
  }
  return view;
}

// The median |depth - truth| (m) over the pixels where both are > 0, and how many they are
// (0 and 0 when none).
inline double MedianAbsError(const FloatMap& depth, const FloatMap& truth, size_t* count) {
  std::vector<double> errors;
  for (size_t p = 0; p < depth.NumPixels(); ++p) {
    if (depth.Data()[p] > 0 && truth.Data()[p] > 0) {
      errors.push_back(std::abs(depth.Data()[p] - truth.Data()[p]));
    }
  }
  *count = errors.size();
  if (errors.empty()) return 0;
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  return errors[errors.size() / 2];
}

}  // namespace testing_util
}  // namespace hairmvs
