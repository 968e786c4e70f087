#pragma once
// The nanoflann k-d tree over float surface / centreline samples shared by the distance
// evaluators (StrandDistance, TriangleMeshDistance): the adaptor, the nearest-primitive
// search with a custom result set, and the parallel batch query.

#include <nanoflann.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

namespace hairmvs {

// nanoflann dataset adaptor over the samples; an evaluator's index derives from it.
struct SampleCloud {
  std::vector<Eigen::Vector3f> samples;

  size_t kdtree_get_point_count() const { return samples.size(); }
  float kdtree_get_pt(uint32_t i, size_t dim) const { return samples[i](dim); }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};

// The most samples an evaluator indexes (about 16 bytes each with the tree's index): a spacing
// far below the data's scale, or a mesh in millimetres read as metres, is refused before the
// samples are made rather than filling the memory.
constexpr double kMaxDistanceSamples = 5e8;

using SampleTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, SampleCloud>,
                                        SampleCloud, 3, uint32_t>;

inline std::unique_ptr<SampleTree> BuildSampleTree(const SampleCloud& cloud) {
  return std::make_unique<SampleTree>(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
}

// Squared search radius for a result set whose nearest primitive is within `radius_m` of
// some sample: slightly generous (float rounding of the tree's distances).
inline float GenerousRadius2(double radius_m) {
  return static_cast<float>(radius_m * radius_m * (1.0 + 1e-5) + 1e-14);
}

// Visits the samples near x with `result` (a nanoflann result set) and returns result.Best().
template <class ResultSet>
double NearestWithResultSet(const SampleTree& tree, const Eigen::Vector3d& x,
                            ResultSet* result) {
  const float query[3] = {static_cast<float>(x(0)), static_cast<float>(x(1)),
                          static_cast<float>(x(2))};
  tree.findNeighbors(*result, query, nanoflann::SearchParams());
  return result->Best();
}

// distance(points[i]) for every point, in parallel.
template <class DistanceFn>
std::vector<double> ParallelDistances(const std::vector<Eigen::Vector3d>& points,
                                      const DistanceFn& distance) {
  std::vector<double> distances(points.size());
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t i = 0; i < points.size(); ++i) distances[i] = distance(points[i]);
  return distances;
}

}  // namespace hairmvs
