#pragma once
// A 3D KD-tree (nanoflann) over a vector of points, for nearest-sample queries.

#include <Eigen/Core>
#include <memory>
#include <nanoflann.hpp>
#include <vector>

namespace hairmvs {

class PointKdTree {
 public:
  PointKdTree(const PointKdTree&) = delete;
  PointKdTree& operator=(const PointKdTree&) = delete;
  explicit PointKdTree(std::vector<Eigen::Vector3d> points)
      : adaptor_{std::move(points)},
        index_(
            std::make_unique<Index>(3, adaptor_, nanoflann::KDTreeSingleIndexAdaptorParams(16))) {
    index_->buildIndex();
  }
  size_t Size() const { return adaptor_.points.size(); }
  const Eigen::Vector3d& Point(size_t i) const { return adaptor_.points[i]; }

  // Up to k nearest points: indices and squared distances, nearest first.
  int Knn(const Eigen::Vector3d& query, int k, uint32_t* indices, double* sq_dists) const {
    return static_cast<int>(index_->knnSearch(query.data(), k, indices, sq_dists));
  }
  double NearestSqDist(const Eigen::Vector3d& query) const {
    uint32_t index;
    double sq_dist = 0;
    Knn(query, 1, &index, &sq_dist);
    return sq_dist;
  }

 private:
  struct Adaptor {
    std::vector<Eigen::Vector3d> points;
    size_t kdtree_get_point_count() const { return points.size(); }
    double kdtree_get_pt(size_t i, size_t dim) const { return points[i][dim]; }
    template <class Bbox>
    bool kdtree_get_bbox(Bbox&) const { return false; }
  };
  using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Adaptor>,
                                                    Adaptor, 3, uint32_t>;
  Adaptor adaptor_;
  std::unique_ptr<Index> index_;
};

}  // namespace hairmvs
