#include "src/synthetic/hair_model.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "src/core/logging.h"
#include "src/evaluation/ground_truth.h"

namespace hairmvs {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Strand growth. Straight hair is simulated in 6 mm steps (the shared sets' point spacing);
// curly hair in 2 mm steps so that the stored points follow a curl of ~12 mm period.
constexpr double kStraightStepM = 0.006;
constexpr double kCurlyStepM = 0.002;
// Bending towards -Z per metre of strand: a strand leaving the scalp horizontally points
// down after ~4 cm, like hair of moderate stiffness.
constexpr double kGravityPerM = 40.0;
// Random bending (radians per sqrt(metre)): keeps straight hair from looking combed by a ruler.
constexpr double kStraightNoise = 0.45;
constexpr double kCurlyNoise = 0.25;
// Layers above the scalp: strand i settles at 1 + 14 * layer mm (plus its curl radius), reached
// over the first 2 cm (or more, see rise_length_m) of its length.
constexpr double kMinLayerM = 0.001;
constexpr double kLayerSpanM = 0.014;
// How far from the head's centre a given strand's point may lie (long hair hangs about 1 m).
constexpr double kMaxHairReachM = 2.0;
constexpr double kLayerRiseM = 0.02;

Eigen::Vector3d RandomUnit(SplitMix64* rng) {
  const double z = rng->Uniform(-1.0, 1.0);
  const double phi = rng->Uniform(0.0, 2.0 * kPi);
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
}

Eigen::Vector3d AnyPerpendicular(const Eigen::Vector3d& t) {
  const Eigen::Vector3d a =
      std::abs(t.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return (a - a.dot(t) * t).normalized();
}

// Dark brown with a per-strand variation in brightness and hue (linear RGB).
Eigen::Vector3f DarkBrownAlbedo(SplitMix64* rng) {
  const double brightness = std::clamp(1.0 + 0.25 * rng->Normal(), 0.5, 1.6);
  const double warmth = rng->Uniform(-0.1, 0.1);
  return Eigen::Vector3f(static_cast<float>(0.036 * brightness * (1 + warmth)),
                         static_cast<float>(0.022 * brightness),
                         static_cast<float>(0.015 * brightness * (1 - warmth)));
}

std::vector<Eigen::Vector3f> GrowStrand(const HeadModel& head, HairStyle style, uint64_t seed,
                                        int index, float* layer_out, Eigen::Vector3f* albedo) {
  SplitMix64 rng(DeriveSeed(seed, 1, static_cast<uint64_t>(index)));
  const bool curly = style == HairStyle::kCurly;

  // Root: a direction on the unit sphere above a hairline that rises from the nape (+Y,
  // z > -0.35) over the sides (z > 0.05) to the forehead (-Y, z > 0.45).
  Eigen::Vector3d u;
  do {
    u = RandomUnit(&rng);
  } while (u.z() < 0.05 - 0.4 * u.y());
  const Eigen::Vector3d root = head.centre + head.semi_axes.cwiseProduct(u);
  const Eigen::Vector3d normal = head.Normal(root);

  const double layer = rng.Uniform();
  const double curl_radius_m = curly ? rng.Uniform(0.003, 0.006) : 0.0;
  const double curl_period_m = curly ? rng.Uniform(0.012, 0.02) : 1.0;
  const double curl_phase = rng.Uniform(0.0, 2.0 * kPi);
  const double offset_m = kMinLayerM + kLayerSpanM * layer + curl_radius_m;
  const double length_m = rng.Uniform(0.16, 0.28) * (curly ? 0.6 : 1.0);
  const double step_m = curly ? kCurlyStepM : kStraightStepM;
  const double noise = (curly ? kCurlyNoise : kStraightNoise) * std::sqrt(step_m);

  // Combed back and outward (away from the face at -Y), then gravity takes over.
  Eigen::Vector3d comb(u.x(), u.y() + 0.5, 0.0);
  if (comb.norm() < 1e-6) comb = Eigen::Vector3d::UnitY();
  comb.normalize();
  comb = (comb - comb.dot(normal) * normal);
  Eigen::Vector3d dir = (normal + 1.2 * comb + 0.15 * RandomUnit(&rng)).normalized();
  // Gravity with a little of the combing direction, so that no strand balances upright.
  const Eigen::Vector3d pull = (Eigen::Vector3d(0, 0, -1) + 0.3 * comb).normalized();
  // The strand rises to its layer at most 0.4 m per metre of length (a steeper rise would
  // turn it radially outward).
  const double rise_length_m = std::max(kLayerRiseM, 2.5 * offset_m);

  const int num_steps = std::max(2, static_cast<int>(std::ceil(length_m / step_m)));
  std::vector<Eigen::Vector3d> guide;
  guide.reserve(num_steps + 1);
  guide.push_back(root);
  Eigen::Vector3d p = root;
  for (int k = 0; k < num_steps; ++k) {
    const Eigen::Vector3d jitter(rng.Normal(), rng.Normal(), rng.Normal());
    dir = (dir + kGravityPerM * step_m * pull + noise * jitter).normalized();
    Eigen::Vector3d next = p + step_m * dir;
    const double rise = std::min(1.0, (k + 1) * step_m / rise_length_m);
    const double shell_m = std::max(0.0003, offset_m * rise);
    // Collision with the strand's own layer: push the point out radially onto the shell, keep
    // the step length. Two rounds settle it to well under a micrometre.
    for (int iter = 0; iter < 3; ++iter) {
      const double q = head.ShellValue(next, shell_m);
      if (q >= 1.0) break;
      next = head.centre + (next - head.centre) / std::sqrt(q) * (1.0 + 1e-9);
      dir = (next - p).normalized();
      next = p + step_m * dir;
    }
    guide.push_back(next);
    p = next;
  }

  std::vector<Eigen::Vector3f> points;
  points.reserve(guide.size());
  if (!curly) {
    for (const auto& g : guide) points.push_back(g.cast<float>());
  } else {
    // Helical curls around the guide path, in a parallel-transported frame; the curl radius
    // ramps up over the first 3 cm so the root stays on the scalp.
    Eigen::Vector3d tangent = (guide[1] - guide[0]).normalized();
    Eigen::Vector3d e1 = AnyPerpendicular(tangent);
    double arc_m = 0.0;
    for (size_t k = 0; k < guide.size(); ++k) {
      if (k > 0) {
        arc_m += (guide[k] - guide[k - 1]).norm();
        const size_t k2 = std::min(k + 1, guide.size() - 1);
        const Eigen::Vector3d t_new = (guide[k2] - guide[k - 1]).normalized();
        e1 = (e1 - e1.dot(t_new) * t_new).normalized();
        tangent = t_new;
      }
      const Eigen::Vector3d e2 = tangent.cross(e1);
      const double theta = curl_phase + 2.0 * kPi * arc_m / curl_period_m;
      const double radius = curl_radius_m * std::min(1.0, arc_m / 0.03);
      points.push_back(
          (guide[k] + radius * (std::cos(theta) * e1 + std::sin(theta) * e2)).cast<float>());
    }
  }

  *albedo = DarkBrownAlbedo(&rng);
  *layer_out = static_cast<float>(layer);
  return points;
}

}  // namespace

uint64_t SplitMix64::Next() {
  uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

double SplitMix64::Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }

double SplitMix64::Normal() {
  const double u1 = 1.0 - Uniform();  // (0, 1]
  const double u2 = Uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

uint64_t DeriveSeed(uint64_t seed, uint64_t stream, uint64_t index) {
  SplitMix64 mix(seed * 0x2545F4914F6CDD1DULL + stream * 0x9E3779B97F4A7C15ULL);
  const uint64_t a = mix.Next();
  SplitMix64 mix2(a ^ (index * 0xD1B54A32D192ED03ULL + 0x632BE59BD9B4E019ULL));
  return mix2.Next();
}

double HeadModel::Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
  // In the frame where the ellipsoid is the unit sphere.
  const Eigen::Vector3d o = (origin - centre).cwiseQuotient(semi_axes);
  const Eigen::Vector3d d = direction.cwiseQuotient(semi_axes);
  const double a = d.squaredNorm();
  const double b = o.dot(d);
  const double c = o.squaredNorm() - 1.0;
  const double h = b * b - a * c;
  if (h < 0.0) return -1.0;
  const double s = std::sqrt(h);
  const double t0 = (-b - s) / a;
  if (t0 > 0.0) return t0;
  const double t1 = (-b + s) / a;
  return t1 > 0.0 ? t1 : -1.0;
}

Eigen::Vector3d HeadModel::Normal(const Eigen::Vector3d& point) const {
  const Eigen::Vector3d q = point - centre;
  return Eigen::Vector3d(q.x() / (semi_axes.x() * semi_axes.x()),
                         q.y() / (semi_axes.y() * semi_axes.y()),
                         q.z() / (semi_axes.z() * semi_axes.z()))
      .normalized();
}

double HeadModel::ShellValue(const Eigen::Vector3d& point, double offset_m) const {
  const Eigen::Vector3d axes = semi_axes.array() + offset_m;
  return (point - centre).cwiseQuotient(axes).squaredNorm();
}

Eigen::Vector3d HairStrands::BoundingBoxCentre() const {
  CHECK(!points.empty());
  Eigen::Vector3f lo = points[0], hi = points[0];
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (0.5f * (lo + hi)).cast<double>();
}

HairStrands GenerateHair(const HeadModel& head, const HairGenerationOptions& options) {
  CHECK_GT(options.num_strands, 0);
  const int n = options.num_strands;
  std::vector<std::vector<Eigen::Vector3f>> strands(n);
  HairStrands hair;
  hair.layer.resize(n);
  hair.albedo.resize(n);
  // Each strand has its own random stream, so the result does not depend on the threads.
#pragma omp parallel for schedule(dynamic, 64)
  for (int i = 0; i < n; ++i) {
    strands[i] = GrowStrand(head, options.style, options.seed, i, &hair.layer[i], &hair.albedo[i]);
  }
  hair.offsets.resize(n + 1);
  hair.offsets[0] = 0;
  for (int i = 0; i < n; ++i) hair.offsets[i + 1] = hair.offsets[i] + strands[i].size();
  hair.points.reserve(hair.offsets[n]);
  for (const auto& s : strands) hair.points.insert(hair.points.end(), s.begin(), s.end());
  return hair;
}

HairStrands HairFromStrands(const HeadModel& head, std::vector<Eigen::Vector3f> points,
                            std::vector<int64_t> offsets, uint64_t seed) {
  THROW_IF(offsets.size() < 2 || offsets.front() != 0 ||
               offsets.back() != static_cast<int64_t>(points.size()),
           "HairFromStrands: the offsets must run from 0 to the number of points ("
               << points.size() << ")");
  // Hair lies around the head: a point metres away (another unit, a stray value) would be
  // densified into billions of points and leave the head unseen.
  for (size_t k = 0; k < points.size(); ++k) {
    const double reach_m = (points[k].cast<double>() - head.centre).norm();
    THROW_IF(!(reach_m <= kMaxHairReachM),
             "HairFromStrands: point " << k << " (" << points[k].transpose() << ") lies "
                                       << reach_m << " m from the head's centre; strands lie "
                                       << "within " << kMaxHairReachM << " m of it, in metres");
  }
  HairStrands hair;
  hair.points = std::move(points);
  hair.offsets = std::move(offsets);
  const int n = hair.NumStrands();
  hair.layer.resize(n);
  hair.albedo.resize(n);
  for (int i = 0; i < n; ++i) {
    const int64_t begin = hair.offsets[i], end = hair.offsets[i + 1];
    THROW_IF(end - begin < 2, "HairFromStrands: strand " << i << " has " << end - begin
                                                          << " point(s); a strand needs 2");
    // Height above the ellipsoid along the ray from its centre: |p - c| (1 - 1 / sqrt(s)),
    // s = ShellValue (1 on the surface).
    std::vector<double> heights;
    for (int64_t k = begin; k < end; ++k) {
      const Eigen::Vector3d p = hair.points[k].cast<double>();
      const double shell = head.ShellValue(p, 0.0);
      heights.push_back(shell > 0 ? (p - head.centre).norm() * (1.0 - 1.0 / std::sqrt(shell))
                                  : 0.0);
    }
    std::nth_element(heights.begin(), heights.begin() + heights.size() / 2, heights.end());
    const double height = heights[heights.size() / 2];
    hair.layer[i] =
        static_cast<float>(std::clamp((height - kMinLayerM) / kLayerSpanM, 0.0, 1.0));
    // Stream 4: GenerateHair's strands use 1, the handheld rig 2, the sparse points 3.
    SplitMix64 rng(DeriveSeed(seed, 4, static_cast<uint64_t>(i)));
    hair.albedo[i] = DarkBrownAlbedo(&rng);
  }
  return hair;
}

DenseStrands DensifyStrands(const HairStrands& hair, double max_spacing_m, double root_diameter_m,
                            double tip_diameter_m) {
  CHECK_GT(max_spacing_m, 0.0);
  const int n = hair.NumStrands();
  // About 28 bytes per point: beyond this the renders would not fit in memory anyway.
  constexpr int64_t kMaxDensePoints = 500'000'000;
  auto segments = [&](int64_t i) {
    const double len = (hair.points[i + 1] - hair.points[i]).norm();
    // Clamped, as a larger double would not convert; a total past the limit is refused below.
    return static_cast<int64_t>(std::clamp(std::ceil(len / max_spacing_m), 1.0,
                                           static_cast<double>(kMaxDensePoints) + 1));
  };
  DenseStrands dense;
  dense.offsets.assign(n + 1, 0);
  for (int s = 0; s < n; ++s) {
    int64_t count = 1;
    for (int64_t i = hair.offsets[s]; i + 1 < hair.offsets[s + 1]; ++i) count += segments(i);
    dense.offsets[s + 1] = dense.offsets[s] + count;
  }
  THROW_IF(dense.offsets[n] > kMaxDensePoints,
           "DensifyStrands: " << n << " strands would take more than " << kMaxDensePoints
                              << " points at one per " << max_spacing_m << " m");
  dense.points.resize(dense.offsets[n]);
  dense.radius_m.resize(dense.offsets[n]);
  dense.strand.resize(dense.offsets[n]);
#pragma omp parallel for schedule(dynamic, 64)
  for (int s = 0; s < n; ++s) {
    const int64_t b = hair.offsets[s], e = hair.offsets[s + 1];
    const int64_t np = e - b;
    auto P = [&](int64_t k) -> Eigen::Vector3d {
      return hair.points[b + std::clamp<int64_t>(k, 0, np - 1)].cast<double>();
    };
    auto radius = [&](double k) {
      const double f = np > 1 ? k / (np - 1) : 0.0;
      return 0.5 * (root_diameter_m + (tip_diameter_m - root_diameter_m) * f);
    };
    int64_t out = dense.offsets[s];
    for (int64_t k = 0; k + 1 < np; ++k) {
      const int64_t m = segments(b + k);
      for (int64_t j = 0; j < m; ++j) {
        const double u = static_cast<double>(j) / m;
        dense.points[out] = CatmullRom(P(k - 1), P(k), P(k + 1), P(k + 2), u).cast<float>();
        dense.radius_m[out] = static_cast<float>(radius(k + u));
        dense.strand[out] = s;
        ++out;
      }
    }
    dense.points[out] = hair.points[e - 1];
    dense.radius_m[out] = static_cast<float>(radius(np - 1));
    dense.strand[out] = s;
    CHECK_EQ(out + 1, dense.offsets[s + 1]);
  }
  return dense;
}

double DistanceToPolyline(const std::vector<Eigen::Vector3f>& points, int64_t begin, int64_t end,
                          const Eigen::Vector3d& x) {
  double best = std::numeric_limits<double>::infinity();
  if (end - begin == 1) return (points[begin].cast<double>() - x).norm();
  for (int64_t i = begin; i + 1 < end; ++i) {
    const Eigen::Vector3d a = points[i].cast<double>(), b = points[i + 1].cast<double>();
    const Eigen::Vector3d ab = b - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((x - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * ab - x).norm());
  }
  return best;
}

}  // namespace hairmvs
