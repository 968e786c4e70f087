#pragma once
// Exact distance from points to a triangle mesh surface: the faces are sampled on a
// barycentric grid (every point of a face within `sample_spacing_m` of one of its samples),
// the samples go into a KD-tree (nanoflann), and each query computes point-to-triangle
// distances for the faces of the samples within (best so far + spacing), which always include
// the nearest face. The spacing only trades memory for speed.

#include <Eigen/Core>
#include <memory>
#include <random>
#include <vector>

namespace hairmvs {

struct TriangleMesh;

// Distance from x to the triangle (a, b, c) (closest point by Voronoi regions; Ericson,
// Real-Time Collision Detection 5.1.5). Degenerate triangles work (segments, points).
double PointTriangleDistance(const Eigen::Vector3d& x, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c);

// Points uniformly distributed over the mesh surface, on average one per spacing^2 of area
// (per face: floor(area / s^2) points plus one more with the remaining probability). Throws
// naming `mesh_source` (the mesh's file) when they would fill the memory.
std::vector<Eigen::Vector3d> SampleMeshSurface(const TriangleMesh& mesh, double spacing_m,
                                               std::mt19937* rng,
                                               const std::string& mesh_source = "mesh");

class TriangleMeshDistance {
 public:
  // Throws naming `mesh_source` (the mesh's file) when the index would fill the memory.
  TriangleMeshDistance(const TriangleMesh& mesh, double sample_spacing_m = 1e-3,
                       const std::string& mesh_source = "mesh");
  ~TriangleMeshDistance();

  double Distance(const Eigen::Vector3d& x) const;
  std::vector<double> Distances(const std::vector<Eigen::Vector3d>& points) const;  // OpenMP

  struct Index;  // samples, faces and the KD-tree (mesh_distance.cc)

 private:
  std::unique_ptr<Index> index_;
};

}  // namespace hairmvs
