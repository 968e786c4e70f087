#include "src/evaluation/mesh_distance.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "colmap_ext/ply.h"
#include "src/core/logging.h"
#include "src/evaluation/sample_kdtree.h"

namespace hairmvs {

double PointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return (a + v * ab - p).norm();
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return (a + w * ac - p).norm();
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return (b + w * (c - b) - p).norm();
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) {
    // Degenerate (collinear) triangle not caught above: nearest of its edges.
    auto seg = [&p](const Eigen::Vector3d& s, const Eigen::Vector3d& e) {
      const Eigen::Vector3d se = e - s;
      const double len2 = se.squaredNorm();
      const double t = len2 > 0 ? std::clamp((p - s).dot(se) / len2, 0.0, 1.0) : 0.0;
      return (s + t * se - p).norm();
    };
    return std::min({seg(a, b), seg(b, c), seg(c, a)});
  }
  const double v = vb / denom, w = vc / denom;
  return (a + ab * v + ac * w - p).norm();
}

std::vector<Eigen::Vector3d> SampleMeshSurface(const TriangleMesh& mesh, double spacing_m,
                                               std::mt19937* rng,
                                               const std::string& mesh_source) {
  CHECK_GT(spacing_m, 0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<Eigen::Vector3d> samples;
  const double cell = spacing_m * spacing_m;
  std::vector<double> face_areas_m2;
  face_areas_m2.reserve(mesh.faces.size());
  double area_m2 = 0;
  for (const Eigen::Vector3i& f : mesh.faces) {
    const Eigen::Vector3d a = mesh.vertices[f(0)].cast<double>();
    face_areas_m2.push_back(0.5 * (mesh.vertices[f(1)].cast<double>() - a)
                                      .cross(mesh.vertices[f(2)].cast<double>() - a)
                                      .norm());
    area_m2 += face_areas_m2.back();
  }
  // Before a per-face count overflows int or the samples fill the memory.
  THROW_IF(area_m2 / cell > kMaxDistanceSamples,
           mesh_source << ": sampling " << area_m2 << " m^2 of mesh every " << spacing_m
                       << " m would take "
                       << area_m2 / cell << " samples; use a larger sample spacing");
  for (size_t face = 0; face < mesh.faces.size(); ++face) {
    const Eigen::Vector3i& f = mesh.faces[face];
    const Eigen::Vector3d a = mesh.vertices[f(0)].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[f(1)].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[f(2)].cast<double>();
    const double expected = face_areas_m2[face] / cell;
    int n = static_cast<int>(std::floor(expected));
    if (uniform(*rng) < expected - n) ++n;
    for (int i = 0; i < n; ++i) {
      double u = uniform(*rng), v = uniform(*rng);
      if (u + v > 1) {
        u = 1 - u;
        v = 1 - v;
      }
      samples.push_back(a + u * (b - a) + v * (c - a));
    }
  }
  return samples;
}

struct TriangleMeshDistance::Index : SampleCloud {
  std::vector<uint32_t> sample_face;
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;
  double spacing_m = 0;
  std::unique_ptr<SampleTree> tree;
};

namespace {

// Keeps the nearest face among those of the visited samples; the search radius shrinks to
// (best + spacing)^2: the nearest face has a sample within `spacing` of the nearest point.
class NearestFaceResult {
 public:
  NearestFaceResult(const TriangleMeshDistance::Index& index, const Eigen::Vector3d& x)
      : index_(index), x_(x) {}
  void init() {}
  void clear() {}
  size_t size() const { return visited_ ? 1 : 0; }
  bool full() const { return true; }
  float worstDist() const { return radius2_; }
  bool addPoint(float, uint32_t i) {
    visited_ = true;
    const uint32_t face = index_.sample_face[i];
    if (face == last_face_) return true;  // consecutive samples mostly share a face
    last_face_ = face;
    const Eigen::Vector3i& f = index_.faces[face];
    const double d = PointTriangleDistance(x_, index_.vertices[f(0)], index_.vertices[f(1)],
                                           index_.vertices[f(2)]);
    if (d < best_) {
      best_ = d;
      radius2_ = GenerousRadius2(best_ + index_.spacing_m);
    }
    return true;
  }
  double Best() const { return best_; }

 private:
  const TriangleMeshDistance::Index& index_;
  Eigen::Vector3d x_;
  bool visited_ = false;
  uint32_t last_face_ = std::numeric_limits<uint32_t>::max();
  double best_ = std::numeric_limits<double>::infinity();
  float radius2_ = std::numeric_limits<float>::infinity();
};

}  // namespace

TriangleMeshDistance::TriangleMeshDistance(const TriangleMesh& mesh, double sample_spacing_m,
                                           const std::string& mesh_source)
    : index_(std::make_unique<Index>()) {
  THROW_IF(!(sample_spacing_m > 0), "TriangleMeshDistance: sample spacing must be > 0");
  THROW_IF(mesh.faces.empty(), "TriangleMeshDistance: the mesh has no faces");
  index_->spacing_m = sample_spacing_m;
  for (const Eigen::Vector3f& v : mesh.vertices) index_->vertices.push_back(v.cast<double>());
  index_->faces = mesh.faces;
  // Barycentric grid with m steps per edge: every point is within longest/m of a grid point.
  std::vector<double> steps(mesh.faces.size());
  double num_samples = 0;
  for (size_t fi = 0; fi < mesh.faces.size(); ++fi) {
    const Eigen::Vector3i& f = mesh.faces[fi];
    for (int k = 0; k < 3; ++k) {
      THROW_IF(f(k) < 0 || f(k) >= static_cast<int>(mesh.vertices.size()),
               "TriangleMeshDistance: face " << fi << " has vertex index " << f(k)
                                             << " out of range");
    }
    const Eigen::Vector3d a = index_->vertices[f(0)];
    const Eigen::Vector3d b = index_->vertices[f(1)];
    const Eigen::Vector3d c = index_->vertices[f(2)];
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    steps[fi] = std::max(1.0, std::ceil(longest / sample_spacing_m));
    num_samples += (steps[fi] + 1) * (steps[fi] + 2) / 2;
  }
  THROW_IF(num_samples > kMaxDistanceSamples,
           mesh_source << ": sampling the " << mesh.faces.size() << " faces every "
                       << sample_spacing_m
                                  << " m would take " << num_samples
                                  << " samples; use a larger sample spacing");
  for (size_t fi = 0; fi < mesh.faces.size(); ++fi) {
    const Eigen::Vector3i& f = mesh.faces[fi];
    const Eigen::Vector3d a = index_->vertices[f(0)];
    const Eigen::Vector3d b = index_->vertices[f(1)];
    const Eigen::Vector3d c = index_->vertices[f(2)];
    const int m = static_cast<int>(steps[fi]);
    for (int i = 0; i <= m; ++i) {
      for (int j = 0; i + j <= m; ++j) {
        const double u = static_cast<double>(i) / m, v = static_cast<double>(j) / m;
        index_->samples.push_back((a + u * (b - a) + v * (c - a)).cast<float>());
        index_->sample_face.push_back(static_cast<uint32_t>(fi));
      }
    }
  }
  index_->tree = BuildSampleTree(*index_);
}

TriangleMeshDistance::~TriangleMeshDistance() = default;

double TriangleMeshDistance::Distance(const Eigen::Vector3d& x) const {
  NearestFaceResult result(*index_, x);
  return NearestWithResultSet(*index_->tree, x, &result);
}

std::vector<double> TriangleMeshDistance::Distances(
    const std::vector<Eigen::Vector3d>& points) const {
  return ParallelDistances(points, [this](const Eigen::Vector3d& x) { return Distance(x); });
}

}  // namespace hairmvs
