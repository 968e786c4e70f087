#include "src/synthetic/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "src/core/logging.h"

namespace hairmvs {
namespace {

constexpr int kBandRows = 8;
// Tube pieces are at most this long on screen when splatted, so the tent filter follows the
// strand's curve.
constexpr double kMaxPiecePx = 0.5;
// Tubes closer than this to the camera are not drawn (never happens in the rigs).
constexpr double kNearM = 0.05;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Smallest root t > 0 of a t^2 + 2 b t + c = 0 with a > 0 (the entry point), or -1.
double EntryRoot(double a, double b, double c) {
  const double h = b * b - a * c;
  if (h < 0.0) return -1.0;
  const double s = std::sqrt(h);
  const double t0 = (-b - s) / a;
  return t0 > 0.0 ? t0 : -1.0;
}

double IntersectSphere(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                       const Eigen::Vector3d& c, double r) {
  const Eigen::Vector3d oc = o - c;
  return EntryRoot(1.0, oc.dot(d), oc.squaredNorm() - r * r);
}

}  // namespace

double IntersectCapsule(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                        const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r) {
  // Move the origin along the ray to just before the capsule, so that the quadratics below
  // work with small numbers (a strand at 0.6 m is 1e-4 m thick).
  const Eigen::Vector3d ba = b - a;
  const double len = ba.norm();
  const double shift = std::max(0.0, (a - origin).dot(dir) - len - r - 1e-6);
  const Eigen::Vector3d o = origin + shift * dir;

  double best = kInf;
  const double len2 = len * len;
  if (len2 > 0.0) {
    // Cylinder body: the component perpendicular to the axis has length r.
    const Eigen::Vector3d oa = o - a;
    const Eigen::Vector3d q = oa - (oa.dot(ba) / len2) * ba;
    const Eigen::Vector3d e = dir - (dir.dot(ba) / len2) * ba;
    const double ee = e.squaredNorm();
    if (ee > 1e-18) {
      const double t = EntryRoot(ee, q.dot(e), q.squaredNorm() - r * r);
      if (t > 0.0) {
        const double y = (oa + t * dir).dot(ba);
        if (y >= 0.0 && y <= len2) best = t;
      }
    }
  }
  const double ta = IntersectSphere(o, dir, a, r);
  if (ta > 0.0) best = std::min(best, ta);
  const double tb = IntersectSphere(o, dir, b, r);
  if (tb > 0.0) best = std::min(best, tb);
  return best < kInf ? best + shift : -1.0;
}

uint8_t LinearToSrgb8(double v) {
  v = std::clamp(v, 0.0, 1.0);
  const double s = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
  return static_cast<uint8_t>(std::lround(s * 255.0));
}

HairScene::HairScene(HeadModel head, DenseStrands strands,
                     std::vector<Eigen::Vector3f> strand_albedo, std::vector<float> strand_layer,
                     RenderSettings settings)
    : head_(std::move(head)),
      strands_(std::move(strands)),
      albedo_(std::move(strand_albedo)),
      layer_(std::move(strand_layer)),
      settings_(std::move(settings)) {
  CHECK_EQ(albedo_.size() + 1, strands_.offsets.size());
  CHECK_EQ(layer_.size() + 1, strands_.offsets.size());
  const int n = static_cast<int>(strands_.offsets.size()) - 1;
  for (int s = 0; s < n; ++s) {
    for (int64_t first = strands_.offsets[s]; first + 1 < strands_.offsets[s + 1]; first += 16) {
      const int64_t last = std::min(first + 16, strands_.offsets[s + 1] - 1);
      Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInf), hi = -lo;
      double r_max = 0;
      for (int64_t i = first; i <= last; ++i) {
        lo = lo.cwiseMin(strands_.points[i].cast<double>());
        hi = hi.cwiseMax(strands_.points[i].cast<double>());
        r_max = std::max(r_max, static_cast<double>(strands_.radius_m[i]));
      }
      blocks_.push_back({0.5 * (lo + hi), 0.5 * (hi - lo).norm() + r_max + 1e-6, first, last});
    }
  }
}

RayHit HairScene::CastRay(const SyntheticView& view, double x, double y) const {
  const Eigen::Vector3d d_cam((x - view.K(0, 2)) / view.K(0, 0),
                              (y - view.K(1, 2)) / view.K(1, 1), 1.0);
  const Eigen::Vector3d dir = d_cam.normalized();
  RayHit hit;
  double best = kInf;
  const Eigen::Vector3d C = view.Centre();
  const double t_head = head_.Intersect(C, view.R.transpose() * d_cam);
  if (t_head > 0.0) {
    best = t_head;
    hit.label = 1;
  }
  const auto& pts = strands_.points;
  const Eigen::Vector3d dir_world = (view.R.transpose() * dir).normalized();
  for (const Block& block : blocks_) {
    const Eigen::Vector3d oc = block.centre - C;
    const double along = oc.dot(dir_world);
    if ((oc - along * dir_world).squaredNorm() > block.radius * block.radius) continue;
    for (int64_t i = block.first; i < block.last; ++i) {
      const Eigen::Vector3d a = view.ToCamera(pts[i].cast<double>());
      const Eigen::Vector3d b = view.ToCamera(pts[i + 1].cast<double>());
      if (a.z() < kNearM || b.z() < kNearM) continue;
      const double r = 0.5 * (strands_.radius_m[i] + strands_.radius_m[i + 1]);
      const double t = IntersectCapsule(Eigen::Vector3d::Zero(), dir, a, b, r);
      if (t > 0.0 && t * dir.z() < best) {
        best = t * dir.z();
        hit.label = 2;
        hit.strand = strands_.strand[i];
      }
    }
  }
  if (hit.label != 0) hit.depth = best;
  return hit;
}

RenderedView HairScene::Render(const SyntheticView& view) const {
  const int W = view.width, H = view.height;
  const double fx = view.K(0, 0), fy = view.K(1, 1), cx = view.K(0, 2), cy = view.K(1, 2);
  const Eigen::Vector3d cam_centre = view.Centre();
  const Eigen::Matrix3d Rt = view.R.transpose();
  const auto& pts = strands_.points;
  const int64_t num_points = static_cast<int64_t>(pts.size());

  // Every strand point in the camera frame and on the image.
  std::vector<Eigen::Vector3f> pc(num_points);
  std::vector<Eigen::Vector2f> uv(num_points);
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < num_points; ++i) {
    const Eigen::Vector3d x = view.ToCamera(pts[i].cast<double>());
    pc[i] = x.cast<float>();
    uv[i] = x.z() > kNearM ? view.Project(x).cast<float>() : Eigen::Vector2f(-1e9f, -1e9f);
  }

  // Tube pieces (chords between consecutive dense points) binned by bands of rows, in index
  // order (CSR), the rows each one can touch: its projected box grown by the tube radius and
  // by the tent filter's reach.
  const int num_bands = (H + kBandRows - 1) / kBandRows;
  auto chord_rows = [&](int64_t i, int* r0, int* r1) {
    if (strands_.strand[i] != strands_.strand[i + 1]) return false;
    const float za = pc[i].z(), zb = pc[i + 1].z();
    if (za < kNearM || zb < kNearM) return false;
    const double r = std::max(strands_.radius_m[i], strands_.radius_m[i + 1]);
    const double r_px = 1.1 * r * fy / (std::min(za, zb) - r) + 1e-3;
    const double vmin = std::min(uv[i].y(), uv[i + 1].y()) - r_px - 1.0;
    const double vmax = std::max(uv[i].y(), uv[i + 1].y()) + r_px + 1.0;
    const double umin = std::min(uv[i].x(), uv[i + 1].x()) - r_px - 1.0;
    const double umax = std::max(uv[i].x(), uv[i + 1].x()) + r_px + 1.0;
    if (vmax < 0 || vmin > H || umax < 0 || umin > W) return false;
    *r0 = std::max(0, static_cast<int>(std::floor(vmin)));
    *r1 = std::min(H - 1, static_cast<int>(std::floor(vmax)));
    return *r0 <= *r1;
  };
  std::vector<int64_t> band_start(num_bands + 1, 0);
  for (int64_t i = 0; i + 1 < num_points; ++i) {
    int r0, r1;
    if (!chord_rows(i, &r0, &r1)) continue;
    for (int b = r0 / kBandRows; b <= r1 / kBandRows; ++b) ++band_start[b + 1];
  }
  for (int b = 0; b < num_bands; ++b) band_start[b + 1] += band_start[b];
  std::vector<int64_t> band_chords(band_start[num_bands]);
  {
    std::vector<int64_t> fill(band_start.begin(), band_start.end() - 1);
    for (int64_t i = 0; i + 1 < num_points; ++i) {
      int r0, r1;
      if (!chord_rows(i, &r0, &r1)) continue;
      for (int b = r0 / kBandRows; b <= r1 / kBandRows; ++b) band_chords[fill[b]++] = i;
    }
  }

  // The head: exact depth at each pixel centre; colour (skin or background) supersampled.
  const Eigen::Vector3d L = settings_.light_direction.normalized();
  std::vector<double> head_depth(static_cast<size_t>(W) * H, kInf);
  std::vector<Eigen::Vector3f> base(static_cast<size_t>(W) * H);
  const int ss = std::max(1, settings_.head_supersampling);
#pragma omp parallel for schedule(dynamic, 4)
  for (int row = 0; row < H; ++row) {
    for (int col = 0; col < W; ++col) {
      const size_t p = static_cast<size_t>(row) * W + col;
      const Eigen::Vector3d d((col + 0.5 - cx) / fx, (row + 0.5 - cy) / fy, 1.0);
      const double t = head_.Intersect(cam_centre, Rt * d);
      if (t > 0.0) head_depth[p] = t;  // d has z = 1: t is the planar depth
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int sy = 0; sy < ss; ++sy) {
        for (int sx = 0; sx < ss; ++sx) {
          const Eigen::Vector3d ds((col + (sx + 0.5) / ss - cx) / fx,
                                   (row + (sy + 0.5) / ss - cy) / fy, 1.0);
          const Eigen::Vector3d dw = Rt * ds;
          const double ts = head_.Intersect(cam_centre, dw);
          if (ts > 0.0) {
            const Eigen::Vector3d n = head_.Normal(cam_centre + ts * dw);
            const double lambert = std::max(0.0, n.dot(L));
            sum += settings_.skin_albedo *
                   (settings_.ambient + settings_.light_intensity * 0.5 * lambert);
          } else {
            sum += settings_.background;
          }
        }
      }
      base[p] = (sum / (ss * ss)).cast<float>();
    }
  }

  RenderedView out;
  out.width = W;
  out.height = H;
  out.rgb.assign(static_cast<size_t>(W) * H * 3, 0);
  out.depth = FloatMap(W, H, 1, 0.0f);
  out.label.assign(static_cast<size_t>(W) * H, 0);
  out.strand_id.assign(static_cast<size_t>(W) * H, -1);
  out.hair_opacity.assign(static_cast<size_t>(W) * H, 0.0f);

#pragma omp parallel for schedule(dynamic, 1)
  for (int band = 0; band < num_bands; ++band) {
    const int row0 = band * kBandRows;
    const int row1 = std::min(H, row0 + kBandRows);  // exclusive
    const size_t band_px = static_cast<size_t>(row1 - row0) * W;
    const size_t first_px = static_cast<size_t>(row0) * W;
    std::vector<double> depth(band_px);
    std::vector<uint8_t> label(band_px);
    std::vector<int32_t> strand(band_px, -1);
    for (size_t k = 0; k < band_px; ++k) {
      depth[k] = head_depth[first_px + k];
      label[k] = depth[k] < kInf ? 1 : 0;
    }

    // Ground truth: exact ray-capsule hits through the pixel centres each piece can cover.
    for (int64_t c = band_start[band]; c < band_start[band + 1]; ++c) {
      const int64_t i = band_chords[c];
      const Eigen::Vector3d a = view.ToCamera(pts[i].cast<double>());
      const Eigen::Vector3d b = view.ToCamera(pts[i + 1].cast<double>());
      const double r = 0.5 * (strands_.radius_m[i] + strands_.radius_m[i + 1]);
      const double r_px = 1.1 * r * std::max(fx, fy) / (std::min(a.z(), b.z()) - r) + 1e-3;
      const double umin = std::min(uv[i].x(), uv[i + 1].x()) - r_px;
      const double umax = std::max(uv[i].x(), uv[i + 1].x()) + r_px;
      const double vmin = std::min(uv[i].y(), uv[i + 1].y()) - r_px;
      const double vmax = std::max(uv[i].y(), uv[i + 1].y()) + r_px;
      const int c0 = std::max(0, static_cast<int>(std::ceil(umin - 0.5)));
      const int c1 = std::min(W - 1, static_cast<int>(std::floor(umax - 0.5)));
      const int q0 = std::max(row0, static_cast<int>(std::ceil(vmin - 0.5)));
      const int q1 = std::min(row1 - 1, static_cast<int>(std::floor(vmax - 0.5)));
      for (int row = q0; row <= q1; ++row) {
        for (int col = c0; col <= c1; ++col) {
          const Eigen::Vector3d dir =
              Eigen::Vector3d((col + 0.5 - cx) / fx, (row + 0.5 - cy) / fy, 1.0).normalized();
          const double t = IntersectCapsule(Eigen::Vector3d::Zero(), dir, a, b, r);
          if (t <= 0.0) continue;
          const double z = t * dir.z();
          const size_t k = static_cast<size_t>(row - row0) * W + col;
          if (z < depth[k]) {
            depth[k] = z;
            label[k] = 2;
            strand[k] = strands_.strand[i];
          }
        }
      }
    }

    // Colour: pieces front to back (by depth, then index: a fixed order).
    std::vector<std::pair<float, int64_t>> order;
    order.reserve(band_start[band + 1] - band_start[band]);
    for (int64_t c = band_start[band]; c < band_start[band + 1]; ++c) {
      const int64_t i = band_chords[c];
      order.emplace_back(0.5f * (pc[i].z() + pc[i + 1].z()), i);
    }
    std::sort(order.begin(), order.end());
    std::vector<Eigen::Vector3f> colour(band_px, Eigen::Vector3f::Zero());
    std::vector<float> transmittance(band_px, 1.0f);
    for (const auto& entry : order) {
      const int64_t i = entry.second;
      const int s = strands_.strand[i];
      // Kajiya-Kay shading with the world tangent; the head's shadow and the depth of the
      // strand's layer darken it (self-shadowing of the hair volume).
      const Eigen::Vector3d pa = pts[i].cast<double>(), pb = pts[i + 1].cast<double>();
      const Eigen::Vector3d seg = pb - pa;
      if (seg.squaredNorm() <= 0.0) continue;
      const Eigen::Vector3d T = seg.normalized();
      const Eigen::Vector3d X = 0.5 * (pa + pb);
      const Eigen::Vector3d V = (cam_centre - X).normalized();
      const double TL = T.dot(L);
      const double diffuse = std::sqrt(std::max(0.0, 1.0 - TL * TL));
      const Eigen::Vector3d Hh = (L + V).normalized();
      const double TH = T.dot(Hh);
      const double spec =
          std::pow(std::sqrt(std::max(0.0, 1.0 - TH * TH)), settings_.specular_exponent);
      const bool shadowed = head_.Intersect(X, L) > 0.0;
      const double facing = std::clamp(0.25 + head_.Normal(X).dot(L), 0.0, 1.0);
      const double lit = shadowed ? 0.0 : facing;
      const double self_shadow = 0.45 + 0.55 * layer_[s];
      const Eigen::Vector3d alb = albedo_[s].cast<double>();
      const Eigen::Vector3f shade =
          (self_shadow * (alb * (settings_.ambient + settings_.light_intensity * diffuse * lit) +
                          Eigen::Vector3d::Constant(settings_.specular *
                                                    settings_.light_intensity * spec * lit)))
              .cast<float>();

      const Eigen::Vector3d ca = pc[i].cast<double>(), cb = pc[i + 1].cast<double>();
      const double r = 0.5 * (strands_.radius_m[i] + strands_.radius_m[i + 1]);
      const double len_px = (uv[i + 1] - uv[i]).cast<double>().norm();
      const int pieces = std::max(1, static_cast<int>(std::ceil(len_px / kMaxPiecePx)));
      for (int k = 0; k < pieces; ++k) {
        const Eigen::Vector3d m = ca + ((k + 0.5) / pieces) * (cb - ca);
        const double u = fx * m.x() / m.z() + cx, v = fy * m.y() / m.z() + cy;
        // Analytic coverage of the piece: projected width x projected length.
        const double area =
            settings_.strand_opacity * (2.0 * r * fx / m.z()) * (len_px / pieces);
        const double gx = u - 0.5, gy = v - 0.5;
        const int col0 = static_cast<int>(std::floor(gx)), rw0 = static_cast<int>(std::floor(gy));
        const double wx = gx - col0, wy = gy - rw0;
        for (int dy = 0; dy < 2; ++dy) {
          const int row = rw0 + dy;
          if (row < row0 || row >= row1) continue;
          for (int dx = 0; dx < 2; ++dx) {
            const int col = col0 + dx;
            if (col < 0 || col >= W) continue;
            const size_t kk = static_cast<size_t>(row - row0) * W + col;
            if (m.z() >= head_depth[first_px + kk] || transmittance[kk] < 1e-4f) continue;
            const double w = (dx ? wx : 1.0 - wx) * (dy ? wy : 1.0 - wy);
            const float alpha = static_cast<float>(std::min(0.98, area * w));
            colour[kk] += transmittance[kk] * alpha * shade;
            transmittance[kk] *= 1.0f - alpha;
          }
        }
      }
    }

    for (size_t k = 0; k < band_px; ++k) {
      const size_t p = first_px + k;
      const Eigen::Vector3f c = colour[k] + transmittance[k] * base[p];
      for (int ch = 0; ch < 3; ++ch) out.rgb[3 * p + ch] = LinearToSrgb8(c[ch]);
      out.hair_opacity[p] = 1.0f - transmittance[k];
      out.label[p] = label[k];
      out.strand_id[p] = strand[k];
      out.depth.Data()[p] = label[k] != 0 ? static_cast<float>(depth[k]) : 0.0f;
    }
  }
  return out;
}

}  // namespace hairmvs
