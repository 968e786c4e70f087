#pragma once
// The ground truth of the synthetic data sets (../shared/data/README.md), stored in NumPy
// files under <set>/gt/:
//   <stem>.npz          depth (H x W float32, z-depth in metres, 0 = nothing hit) and
//                       label (H x W uint8: 0 background, 1 head skin, 2 hair), both sampled at
//                       the pixel centres (SfM convention)
//   cameras.npz         names (<U), R (n,3,3), t (n,3), C (n,3), K (3,3), width, height,
//                       hair_centre (3,): X_cam = R X_world + t
//   strands_points.npy  (N,3) float32 world points; strands_offsets.npy (S+1,) int64:
//                       strand i is points[offsets[i]:offsets[i+1]], root first

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "src/core/float_map.h"

namespace hairmvs {

enum GroundTruthLabel : uint8_t { kLabelBackground = 0, kLabelSkin = 1, kLabelHair = 2 };

struct GroundTruthView {
  FloatMap depth;              // W x H x 1, metres, 0 = background
  std::vector<uint8_t> label;  // H * W, row-major
};

// gt_path/<stem of image_name>.npz ("g0_c.png" -> gt_path/g0_c.npz). Throws hairmvs::Error
// naming the file when it is missing or its arrays are not H x W float32 / uint8.
std::string GroundTruthViewPath(const std::string& gt_path, const std::string& image_name);
// Throws hairmvs::Error "Missing ground truth folder (a data set's gt/): gt_path" unless it is a
// folder. The readers below check it first, so that a wrong --ground_truth_path (or
// synthesize's --strands_path) is named as such, not as the first file missing from it.
void RequireGroundTruthDir(const std::string& gt_path);
// gt_path/cameras.npz.
std::string GroundTruthCamerasPath(const std::string& gt_path);
GroundTruthView ReadGroundTruthView(const std::string& gt_path, const std::string& image_name);
void WriteGroundTruthView(const std::string& gt_path, const std::string& image_name,
                          const GroundTruthView& view);

struct GroundTruthCameras {
  std::vector<std::string> names;
  std::vector<Eigen::Matrix3d> R;  // cam_from_world rotation
  std::vector<Eigen::Vector3d> t;  // cam_from_world translation
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();  // SfM pixel convention
  int width = 0;
  int height = 0;
  Eigen::Vector3d hair_centre = Eigen::Vector3d::Zero();

  // Index of `name` in names; -1 when absent.
  int Find(const std::string& name) const;
  Eigen::Vector3d Center(int i) const { return -(R[i].transpose() * t[i]); }
};
GroundTruthCameras ReadGroundTruthCameras(const std::string& gt_path);
void WriteGroundTruthCameras(const std::string& gt_path, const GroundTruthCameras& cameras);

struct GroundTruthStrands {
  std::vector<Eigen::Vector3f> points;
  std::vector<int64_t> offsets;  // size = number of strands + 1, offsets[0] = 0
  size_t NumStrands() const { return offsets.empty() ? 0 : offsets.size() - 1; }
};
GroundTruthStrands ReadGroundTruthStrands(const std::string& gt_path);
void WriteGroundTruthStrands(const std::string& gt_path, const GroundTruthStrands& strands);

// The uniform Catmull-Rom spline through p0..p3 between p1 (u = 0) and p2 (u = 1).
Eigen::Vector3d CatmullRom(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                           const Eigen::Vector3d& p2, const Eigen::Vector3d& p3, double u);

// Distance from a point to the nearest true strand centreline. The renders are tubes around
// the uniform Catmull-Rom spline through each strand's stored points (end points repeated, as
// Cycles and Blender do), whose points are ~6 mm apart: each spline segment is sampled so
// consecutive samples are at most max_spacing_m apart, the samples go into a KD-tree
// (nanoflann), and the distance is the exact distance to the polyline through the samples
// (within ~ spacing^2 / (8 * radius of curvature) of the spline). Thread-safe queries.
// Memory: ~30 bytes per sample (40 000 strands of 20 cm at 0.2 mm: ~1.2 GB).
class StrandDistance {
 public:
  explicit StrandDistance(const GroundTruthStrands& strands, double max_spacing_m = 1e-3);
  ~StrandDistance();

  double Distance(const Eigen::Vector3d& x) const;
  // Distances of many points, in parallel (OpenMP).
  std::vector<double> Distances(const std::vector<Eigen::Vector3d>& points) const;
  size_t NumSamples() const;

  struct Index;  // the samples and the KD-tree (ground_truth.cc)

 private:
  std::unique_ptr<Index> index_;
};

}  // namespace hairmvs
