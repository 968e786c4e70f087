#pragma once
// Test scenes for template fusion: implicit surfaces (signed distance functions) ray-marched
// into z-depth and normal maps from PINHOLE cameras around them. Header-only, for tests.

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "src/core/depth_geometry.h"
#include "src/fusion/fusion_view.h"

namespace hairmvs {
namespace testing {

using Sdf = std::function<double(const Eigen::Vector3d&)>;

inline Sdf SphereSdf(double radius) {
  return [radius](const Eigen::Vector3d& p) { return p.norm() - radius; };
}
// Torus around the z axis.
inline Sdf TorusSdf(double major, double minor) {
  return [major, minor](const Eigen::Vector3d& p) {
    const double q = std::hypot(p.x(), p.y()) - major;
    return std::hypot(q, p.z()) - minor;
  };
}
// A sphere whose radius ripples by +-amplitude with `frequency` periods per radian in
// longitude and latitude: high frequencies for the detail step.
inline Sdf RippledSphereSdf(double radius, double amplitude, double frequency) {
  return [=](const Eigen::Vector3d& p) {
    const double lon = std::atan2(p.y(), p.x());
    const double lat = std::asin(std::clamp(p.z() / std::max(p.norm(), 1e-12), -1.0, 1.0));
    return p.norm() - (radius + amplitude * std::sin(frequency * lon) * std::cos(lat) *
                                    std::sin(frequency * lat));
  };
}

inline Eigen::Vector3d SdfGradient(const Sdf& sdf, const Eigen::Vector3d& p) {
  const double h = 1e-5;
  Eigen::Vector3d g;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[k] = h;
    g[k] = (sdf(p + e) - sdf(p - e)) / (2 * h);
  }
  return g;
}

// First-order distance to the zero set: |f| / |grad f|.
inline double SurfaceDistance(const Sdf& sdf, const Eigen::Vector3d& p) {
  return std::abs(sdf(p)) / std::max(SdfGradient(sdf, p).norm(), 1e-9);
}

// A camera at `center` looking at the origin, world +z up.
inline void LookAt(const Eigen::Vector3d& center, Eigen::Matrix3d* R, Eigen::Vector3d* t) {
  const Eigen::Vector3d z = (-center).normalized();
  Eigen::Vector3d up(0, 0, 1);
  if (std::abs(z.dot(up)) > 0.99) up = Eigen::Vector3d(0, 1, 0);
  const Eigen::Vector3d x = z.cross(up).normalized();  // camera x right, y down
  const Eigen::Vector3d y = z.cross(x);
  R->row(0) = x;
  R->row(1) = y;
  R->row(2) = z;
  *t = -*R * center;
}

struct SceneOptions {
  int width = 96, height = 72;
  double focal_px = 90;
  double distance = 4.0;
  int num_azimuths = 6;
  std::vector<double> elevations_deg = {-40, 40};
  double depth_noise = 0;  // Gaussian sigma on depth, scene units
  // Each view's pose given to the fusion is off the true one by rotations and translations
  // of this order (radians, scene units): calibration error.
  double misalignment_rad = 0;
  double misalignment_translation = 0;
  unsigned seed = 7;
};

// Renders depth (pixel centres, SfM convention) and camera-facing normals by sphere tracing.
inline std::vector<FusionView> RenderViews(const Sdf& sdf, const SceneOptions& o) {
  std::mt19937 rng(o.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<FusionView> views;
  Eigen::Matrix3d K;
  K << o.focal_px, 0, o.width / 2.0, 0, o.focal_px, o.height / 2.0, 0, 0, 1;
  for (double elevation_deg : o.elevations_deg) {
    for (int a = 0; a < o.num_azimuths; ++a) {
      const double az = 2 * M_PI * (a + (elevation_deg > 0 ? 0.5 : 0.0)) / o.num_azimuths;
      const double el = elevation_deg * M_PI / 180;
      const Eigen::Vector3d center =
          o.distance * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                       std::sin(el));
      FusionView view;
      view.name = "view" + std::to_string(views.size()) + ".png";
      view.K = K;
      LookAt(center, &view.R, &view.t);
      view.depth = FloatMap(o.width, o.height, 1, 0.0f);
      view.normal = FloatMap(o.width, o.height, 3, 0.0f);
      view.rgb = FloatMap(o.width, o.height, 3, 0.5f);
      for (int row = 0; row < o.height; ++row) {
        for (int col = 0; col < o.width; ++col) {
          const Eigen::Vector3d ray_cam = BackProjectPixel(K, col, row, 1.0);  // z = 1
          const Eigen::Vector3d dir = view.R.transpose() * ray_cam;
          double s = 0;
          bool hit = false;
          for (int it = 0; it < 400 && s < 2 * o.distance; ++it) {
            const double d = sdf(center + s * dir);
            if (d < 1e-6) {
              hit = true;
              break;
            }
            s += 0.7 * d;  // under-relaxed: the rippled "SDF" is not exactly 1-Lipschitz
          }
          if (!hit) continue;
          const Eigen::Vector3d p = center + s * dir;
          Eigen::Vector3d n = view.R * SdfGradient(sdf, p).normalized();
          if (n.dot(ray_cam) > 0) n = -n;
          view.depth.At(row, col) = static_cast<float>(s + o.depth_noise * gauss(rng));
          for (int k = 0; k < 3; ++k) view.normal.At(row, col, k) = static_cast<float>(n[k]);
          const double shade = 0.3 + 0.6 * std::abs(n.z());
          for (int k = 0; k < 3; ++k) view.rgb.At(row, col, k) = static_cast<float>(shade);
        }
      }
      if (o.misalignment_rad > 0 || o.misalignment_translation > 0) {
        const Eigen::Vector3d axis(gauss(rng), gauss(rng), gauss(rng));
        const Eigen::Matrix3d dR =
            Eigen::AngleAxisd(o.misalignment_rad, axis.normalized()).toRotationMatrix();
        view.R = dR * view.R;
        view.t = dR * view.t + o.misalignment_translation *
                                   Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
      }
      views.push_back(std::move(view));
    }
  }
  return views;
}

}  // namespace testing
}  // namespace hairmvs
