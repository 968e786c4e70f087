#include "src/evaluation/ground_truth.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "colmap_ext/reconstruction.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/npz.h"
#include "src/evaluation/sample_kdtree.h"

namespace hairmvs {
namespace {

// Checks that `array` has exactly `shape` (names the file and array otherwise).
void RequireShape(const NpyArray& array, const std::vector<size_t>& shape,
                  const std::string& what) {
  auto text = [](const std::vector<size_t>& s) {
    std::string out = "(";
    for (size_t i = 0; i < s.size(); ++i) out += (i ? ", " : "") + std::to_string(s[i]);
    return out + ")";
  };
  THROW_IF(array.shape != shape,
           what << ": expected shape " << text(shape) << ", found " << text(array.shape));
}

// Throws naming `what` and the first element that is nan or inf.
void RequireFinite(const std::vector<double>& values, const std::string& what) {
  for (size_t i = 0; i < values.size(); ++i) {
    THROW_IF(!std::isfinite(values[i]),
             what << ": element " << i << " is " << values[i] << "; every element must be finite");
  }
}

// Throws naming `what` and the first element that is nan, inf or negative (depths).
void RequireFiniteNonNegative(const std::vector<float>& values, const std::string& what) {
  for (size_t i = 0; i < values.size(); ++i) {
    THROW_IF(!std::isfinite(values[i]) || values[i] < 0,
             what << ": element " << i << " is " << values[i]
                  << "; every element must be finite and >= 0");
  }
}

// A scalar that is a whole number of pixels in [1, kMaxCameraSizePx] (the model readers' limit).
int ImageSize(const NpyArray& array, const std::string& what) {
  THROW_IF(array.NumElements() != 1, what << ": must be a scalar");
  const double value = array.ToVector<double>(what)[0];
  THROW_IF(!(value >= 1 && value <= static_cast<double>(kMaxCameraSizePx)) ||
               value != std::floor(value),
           what << ": " << value << " is not a whole number of pixels in 1.." << kMaxCameraSizePx);
  return static_cast<int>(value);
}

}  // namespace

void RequireGroundTruthDir(const std::string& gt_path) {
  RequireDir(gt_path, "ground truth folder (a data set's gt/)");
}

std::string GroundTruthViewPath(const std::string& gt_path, const std::string& image_name) {
  std::string stem = image_name;
  const size_t slash = stem.find_last_of('/');
  const size_t dot = stem.find_last_of('.');
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) stem.resize(dot);
  return JoinPaths(gt_path, stem + ".npz");
}

GroundTruthView ReadGroundTruthView(const std::string& gt_path, const std::string& image_name) {
  RequireGroundTruthDir(gt_path);
  const std::string path = GroundTruthViewPath(gt_path, image_name);
  const auto arrays = ReadNpz(path);
  const NpyArray& depth = NpzEntry(arrays, "depth", path);
  const NpyArray& label = NpzEntry(arrays, "label", path);
  THROW_IF(depth.shape.size() != 2, path << ": depth must be H x W, has " << depth.shape.size()
                                         << " dimensions");
  const size_t height = depth.shape[0];
  const size_t width = depth.shape[1];
  // Named against depth: either of the two may be the wrong one.
  RequireShape(label, {height, width}, path + ": label (the shape of depth)");
  // Depths in metres, 0 where nothing was hit; labels 0 (background), 1 (head skin), 2 (hair).
  GroundTruthView view;
  view.depth = FloatMap(static_cast<int>(width), static_cast<int>(height), 1);
  view.depth.Data() = depth.ToVector<float>(path + ": depth");
  RequireFiniteNonNegative(view.depth.Data(), path + ": depth");
  THROW_IF(!label.IsInteger(),
           path << ": label must be an integer array (0 background, 1 head skin, 2 hair), found "
                   "dtype "
                << label.dtype);
  const std::vector<int64_t> labels = label.ToVector<int64_t>(path + ": label");
  for (size_t i = 0; i < labels.size(); ++i) {
    THROW_IF(labels[i] < 0 || labels[i] > 2,
             path << ": label of pixel (" << i % width << ", " << i / width << ") is "
                  << labels[i] << "; labels are 0 (background), 1 (head skin) or 2 (hair)");
  }
  view.label.assign(labels.begin(), labels.end());
  return view;
}

void WriteGroundTruthView(const std::string& gt_path, const std::string& image_name,
                          const GroundTruthView& view) {
  CHECK_EQ(view.depth.Channels(), 1);
  CHECK_EQ(view.label.size(), view.depth.NumPixels());
  const std::vector<size_t> shape = {static_cast<size_t>(view.depth.Height()),
                                     static_cast<size_t>(view.depth.Width())};
  std::map<std::string, NpyArray> arrays;
  arrays["depth"] = NpyArray::FromVector(view.depth.Data(), shape);
  arrays["label"] = NpyArray::FromVector(view.label, shape);
  WriteNpz(GroundTruthViewPath(gt_path, image_name), arrays);
}

std::string GroundTruthCamerasPath(const std::string& gt_path) {
  return JoinPaths(gt_path, "cameras.npz");
}

int GroundTruthCameras::Find(const std::string& name) const {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

GroundTruthCameras ReadGroundTruthCameras(const std::string& gt_path) {
  RequireGroundTruthDir(gt_path);
  const std::string path = GroundTruthCamerasPath(gt_path);
  const auto arrays = ReadNpz(path);
  GroundTruthCameras cameras;
  cameras.names = NpzEntry(arrays, "names", path).Strings(path + ": names");
  const size_t n = cameras.names.size();
  const NpyArray& R = NpzEntry(arrays, "R", path);
  const NpyArray& t = NpzEntry(arrays, "t", path);
  const NpyArray& K = NpzEntry(arrays, "K", path);
  RequireShape(R, {n, 3, 3}, path + ": R");
  RequireShape(t, {n, 3}, path + ": t");
  RequireShape(K, {3, 3}, path + ": K");
  const std::vector<double> r = R.ToVector<double>(path + ": R");
  const std::vector<double> tv = t.ToVector<double>(path + ": t");
  const std::vector<double> k = K.ToVector<double>(path + ": K");
  RequireFinite(r, path + ": R");
  RequireFinite(tv, path + ": t");
  RequireFinite(k, path + ": K");
  THROW_IF(!(k[0] > 0 && k[4] > 0),
           path << ": K's focal lengths (" << k[0] << ", " << k[4] << ") must be > 0");
  for (size_t i = 0; i < n; ++i) {
    // C order: R[i][row][col].
    cameras.R.push_back(Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(
        r.data() + 9 * i));
    cameras.t.emplace_back(tv[3 * i], tv[3 * i + 1], tv[3 * i + 2]);
    const Eigen::Matrix3d& rotation = cameras.R.back();
    const double off = (rotation * rotation.transpose() - Eigen::Matrix3d::Identity())
                           .cwiseAbs()
                           .maxCoeff();
    THROW_IF(off > 1e-3 || rotation.determinant() < 0,
             path << ": R[" << i << "] (" << cameras.names[i] << ") is no rotation ("
                  << (off > 1e-3 ? "not orthonormal" : "a reflection") << ")");
  }
  cameras.K = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(k.data());
  cameras.width = ImageSize(NpzEntry(arrays, "width", path), path + ": width");
  cameras.height = ImageSize(NpzEntry(arrays, "height", path), path + ": height");
  const auto centre = arrays.find("hair_centre");
  if (centre != arrays.end() && centre->second.NumElements() == 3) {
    const std::vector<double> xyz = centre->second.ToVector<double>(path + ": hair_centre");
    RequireFinite(xyz, path + ": hair_centre");
    for (int j = 0; j < 3; ++j) cameras.hair_centre(j) = xyz[j];
  }
  return cameras;
}

void WriteGroundTruthCameras(const std::string& gt_path, const GroundTruthCameras& cameras) {
  const size_t n = cameras.names.size();
  CHECK_EQ(cameras.R.size(), n);
  CHECK_EQ(cameras.t.size(), n);
  std::vector<double> r, t, c;
  for (size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) r.push_back(cameras.R[i](a, b));
      t.push_back(cameras.t[i](a));
      c.push_back(cameras.Center(static_cast<int>(i))(a));
    }
  }
  std::vector<double> k;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) k.push_back(cameras.K(a, b));
  }
  std::map<std::string, NpyArray> arrays;
  arrays["names"] = NpyArray::FromStrings(cameras.names);
  arrays["R"] = NpyArray::FromVector(r, {n, 3, 3});
  arrays["t"] = NpyArray::FromVector(t, {n, 3});
  arrays["C"] = NpyArray::FromVector(c, {n, 3});
  arrays["K"] = NpyArray::FromVector(k, {3, 3});
  arrays["width"] = NpyArray::Scalar<int64_t>(cameras.width);
  arrays["height"] = NpyArray::Scalar<int64_t>(cameras.height);
  arrays["hair_centre"] = NpyArray::FromVector(
      std::vector<double>{cameras.hair_centre(0), cameras.hair_centre(1), cameras.hair_centre(2)});
  WriteNpz(GroundTruthCamerasPath(gt_path), arrays);
}

GroundTruthStrands ReadGroundTruthStrands(const std::string& gt_path) {
  RequireGroundTruthDir(gt_path);
  const std::string points_path = JoinPaths(gt_path, "strands_points.npy");
  const std::string offsets_path = JoinPaths(gt_path, "strands_offsets.npy");
  const NpyArray points = ReadNpy(points_path);
  const NpyArray offsets = ReadNpy(offsets_path);
  THROW_IF(points.shape.size() != 2 || points.shape[1] != 3,
           points_path << ": expected an (N, 3) array");
  THROW_IF(offsets.shape.size() != 1 || offsets.shape[0] < 1,
           offsets_path << ": expected an (S+1,) array");
  GroundTruthStrands strands;
  const std::vector<float> xyz = points.ToVector<float>(points_path);
  strands.points.resize(points.shape[0]);
  for (size_t i = 0; i < strands.points.size(); ++i) {
    strands.points[i] = Eigen::Vector3f(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    THROW_IF(!strands.points[i].allFinite(),
             points_path << ": point " << i << " is not finite (" << xyz[3 * i] << ", "
                         << xyz[3 * i + 1] << ", " << xyz[3 * i + 2] << ")");
  }
  strands.offsets = offsets.ToVector<int64_t>(offsets_path);
  THROW_IF(strands.offsets.front() != 0 ||
               strands.offsets.back() != static_cast<int64_t>(strands.points.size()),
           offsets_path << ": offsets must start at 0 and end at the number of points ("
                        << strands.points.size() << ")");
  for (size_t i = 1; i < strands.offsets.size(); ++i) {
    THROW_IF(strands.offsets[i] < strands.offsets[i - 1],
             offsets_path << ": offsets decrease at index " << i);
  }
  return strands;
}

void WriteGroundTruthStrands(const std::string& gt_path, const GroundTruthStrands& strands) {
  std::vector<float> xyz;
  xyz.reserve(3 * strands.points.size());
  for (const Eigen::Vector3f& p : strands.points) xyz.insert(xyz.end(), {p(0), p(1), p(2)});
  WriteNpy(JoinPaths(gt_path, "strands_points.npy"),
           NpyArray::FromVector(xyz, {strands.points.size(), 3}));
  WriteNpy(JoinPaths(gt_path, "strands_offsets.npy"), NpyArray::FromVector(strands.offsets));
}

Eigen::Vector3d CatmullRom(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                           const Eigen::Vector3d& p2, const Eigen::Vector3d& p3, double u) {
  const double u2 = u * u;
  const double u3 = u2 * u;
  return 0.5 * (2.0 * p1 + (p2 - p0) * u + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * u2 +
                (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * u3);
}

// --- StrandDistance ---------------------------------------------------------------------------

struct StrandDistance::Index : SampleCloud {
  // samples: the densified centreline; connected[i] says whether sample i and i+1 belong to
  // the same strand (the polyline continues).
  std::vector<uint8_t> connected;
  double max_segment_m = 0;
  std::unique_ptr<SampleTree> tree;
};

namespace {

double PointSegmentDistanceSquared(const Eigen::Vector3d& x, const Eigen::Vector3d& a,
                                   const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  double s = len2 > 0 ? (x - a).dot(ab) / len2 : 0.0;
  s = std::clamp(s, 0.0, 1.0);
  return (a + s * ab - x).squaredNorm();
}

// A nanoflann result set that keeps the distance to the nearest polyline segment touching a
// visited sample. Its search radius shrinks to (best + h/2)^2, h = the longest segment: the
// nearest point of the polyline lies on a segment one of whose end points is within h/2 of
// it, so that end point is within best + h/2 of the query and is never pruned.
class NearestSegmentResult {
 public:
  NearestSegmentResult(const StrandDistance::Index& index, const Eigen::Vector3d& x)
      : index_(index), x_(x) {}

  void init() {}
  void clear() {}
  size_t size() const { return visited_ ? 1 : 0; }
  bool full() const { return true; }
  float worstDist() const { return radius2_; }

  bool addPoint(float, uint32_t i) {
    visited_ = true;
    const Eigen::Vector3d p = index_.samples[i].cast<double>();
    double d2 = (p - x_).squaredNorm();
    if (i > 0 && index_.connected[i - 1]) {
      d2 = std::min(d2, PointSegmentDistanceSquared(x_, index_.samples[i - 1].cast<double>(), p));
    }
    if (index_.connected[i]) {
      d2 = std::min(d2, PointSegmentDistanceSquared(x_, p, index_.samples[i + 1].cast<double>()));
    }
    if (d2 < best2_) {
      best2_ = d2;
      radius2_ = GenerousRadius2(std::sqrt(best2_) + 0.5 * index_.max_segment_m);
    }
    return true;
  }

  double Best() const { return std::sqrt(best2_); }

 private:
  const StrandDistance::Index& index_;
  Eigen::Vector3d x_;
  bool visited_ = false;
  double best2_ = std::numeric_limits<double>::infinity();
  float radius2_ = std::numeric_limits<float>::infinity();
};

}  // namespace

StrandDistance::StrandDistance(const GroundTruthStrands& strands, double max_spacing_m)
    : index_(std::make_unique<Index>()) {
  THROW_IF(!(max_spacing_m > 0), "StrandDistance: max_spacing_m must be > 0");
  THROW_IF(strands.points.empty(), "StrandDistance: no strand points");
  // Segment k of the strand of n points at `begin`: its spline's four control points (end
  // points repeated: the spline starts at the root and ends at the tip) and the steps that
  // sample it no further apart than max_spacing_m (its arc length bounded by the Bezier control
  // polygon). Steps in double: a tiny spacing must be refused below, not overflow an int.
  struct Segment {
    Eigen::Vector3d p[4];
    double steps = 1;
  };
  const auto segment = [&](int64_t begin, int64_t n, int64_t k) {
    Segment seg;
    for (int i = 0; i < 4; ++i) {
      seg.p[i] = strands.points[begin + std::clamp<int64_t>(k - 1 + i, 0, n - 1)].cast<double>();
    }
    const Eigen::Vector3d b1 = seg.p[1] + (seg.p[2] - seg.p[0]) / 6.0;
    const Eigen::Vector3d b2 = seg.p[2] - (seg.p[3] - seg.p[1]) / 6.0;
    const double length_bound = (b1 - seg.p[1]).norm() + (b2 - b1).norm() + (seg.p[2] - b2).norm();
    seg.steps = std::max(1.0, std::ceil(length_bound / max_spacing_m));
    return seg;
  };
  double num_samples = 0;
  for (size_t s = 0; s < strands.NumStrands(); ++s) {
    const int64_t n = strands.offsets[s + 1] - strands.offsets[s];
    if (n > 0) num_samples += 1;
    for (int64_t k = 0; k + 1 < n; ++k) num_samples += segment(strands.offsets[s], n, k).steps;
  }
  THROW_IF(num_samples > kMaxDistanceSamples,
           "Sampling the true strands every " << max_spacing_m << " m would take " << num_samples
                                              << " samples; use a larger strand spacing");
  std::vector<Eigen::Vector3f>& samples = index_->samples;
  std::vector<uint8_t>& connected = index_->connected;
  samples.reserve(static_cast<size_t>(num_samples));
  connected.reserve(static_cast<size_t>(num_samples));
  for (size_t s = 0; s < strands.NumStrands(); ++s) {
    const int64_t begin = strands.offsets[s];
    const int64_t n = strands.offsets[s + 1] - begin;
    if (n <= 0) continue;
    samples.push_back(strands.points[begin]);
    connected.push_back(1);
    for (int64_t k = 0; k + 1 < n; ++k) {
      const Segment seg = segment(begin, n, k);
      const int steps = static_cast<int>(seg.steps);
      for (int j = 1; j <= steps; ++j) {
        samples.push_back(CatmullRom(seg.p[0], seg.p[1], seg.p[2], seg.p[3],
                                     static_cast<double>(j) / steps)
                              .cast<float>());
        connected.push_back(1);
      }
    }
    connected.back() = 0;
  }
  for (size_t i = 0; i + 1 < samples.size(); ++i) {
    if (connected[i]) {
      index_->max_segment_m = std::max(
          index_->max_segment_m, static_cast<double>((samples[i + 1] - samples[i]).norm()));
    }
  }
  index_->tree = BuildSampleTree(*index_);
}

StrandDistance::~StrandDistance() = default;

size_t StrandDistance::NumSamples() const { return index_->samples.size(); }

double StrandDistance::Distance(const Eigen::Vector3d& x) const {
  NearestSegmentResult result(*index_, x);
  return NearestWithResultSet(*index_->tree, x, &result);
}

std::vector<double> StrandDistance::Distances(const std::vector<Eigen::Vector3d>& points) const {
  return ParallelDistances(points, [this](const Eigen::Vector3d& x) { return Distance(x); });
}

}  // namespace hairmvs
