#include "src/fusion/poisson_template.h"

#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/utility/Logging.h>

#include <algorithm>
#include <cmath>

#include "src/core/logging.h"
#include "src/fusion/point_kdtree.h"

namespace hairmvs {
namespace {

FusionMesh FromOpen3D(const open3d::geometry::TriangleMesh& mesh) {
  FusionMesh out;
  out.vertices = mesh.vertices_;
  out.faces = mesh.triangles_;
  return out;
}

open3d::geometry::TriangleMesh ToOpen3D(const FusionMesh& mesh) {
  open3d::geometry::TriangleMesh out;
  out.vertices_ = mesh.vertices;
  out.triangles_ = mesh.faces;
  return out;
}

}  // namespace

double PoissonCellSize(const FusionPoints& points, const TemplateFusionOptions& options) {
  CHECK(!points.xyz.empty());
  Eigen::Vector3f lo = points.xyz[0], hi = points.xyz[0];
  for (const Eigen::Vector3f& p : points.xyz) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).maxCoeff() * options.poisson_scale / std::ldexp(1.0, options.poisson_depth);
}

FusionMesh PoissonTemplate(const FusionPoints& samples, const TemplateFusionOptions& options,
                           double cell_m, double sample_spacing_m) {
  open3d::utility::SetVerbosityLevel(open3d::utility::VerbosityLevel::Error);
  open3d::geometry::PointCloud cloud;
  cloud.points_.reserve(samples.Size());
  cloud.normals_.reserve(samples.Size());
  for (size_t i = 0; i < samples.Size(); ++i) {
    cloud.points_.push_back(samples.xyz[i].cast<double>());
    cloud.normals_.push_back(samples.normal[i].cast<double>());
  }
  // One thread: at depth 6 Poisson takes ~1 s, and Open3D's OpenMP threads spin so badly on
  // a busy 2-core machine that 2 threads took 20 s where 1 took 1.3 s (measured).
  auto [poisson_mesh, densities] = open3d::geometry::TriangleMesh::CreateFromPointCloudPoisson(
      cloud, static_cast<size_t>(options.poisson_depth), 0.0f,
      static_cast<float>(options.poisson_scale), false, /*n_threads=*/1);
  FusionMesh mesh = FromOpen3D(*poisson_mesh);
  if (mesh.faces.empty()) return mesh;

  // Trim the low-density parts: where no sample lies within trim_distance_cells, Poisson only
  // closed the surface (it is watertight by construction), e.g. under the hair or at the crown.
  const PointKdTree tree(cloud.points_);
  // Samples may be sparser than the octree (fine octree, coarse depth maps): never trim
  // closer than trim_min_sample_spacings.
  const double max_sq_dist =
      std::pow(std::max(options.trim_distance_cells * cell_m,
                        options.trim_min_sample_spacings * sample_spacing_m),
               2);
  std::vector<bool> keep(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& face = mesh.faces[f];
    const Eigen::Vector3d centroid =
        (mesh.vertices[face[0]] + mesh.vertices[face[1]] + mesh.vertices[face[2]]) / 3.0;
    keep[f] = tree.NearestSqDist(centroid) <= max_sq_dist;
  }
  mesh.KeepFaces(keep);

  // Small islands left by the trimming are noise, not hair.
  int num_components = 0;
  const std::vector<int> component = mesh.FaceComponents(&num_components);
  std::vector<int> size(num_components, 0);
  for (int c : component) ++size[c];
  const int largest = num_components > 0 ? *std::max_element(size.begin(), size.end()) : 0;
  std::vector<bool> keep_component(component.size());
  for (size_t f = 0; f < component.size(); ++f) {
    keep_component[f] = size[component[f]] >= options.min_component_fraction * largest;
  }
  mesh.KeepFaces(keep_component);
  mesh.ComputeVertexNormals();
  return mesh;
}

FusionMesh SubdivideLoop(const FusionMesh& mesh, int iterations) {
  if (iterations <= 0 || mesh.faces.empty()) return mesh;
  const open3d::geometry::TriangleMesh o3d = ToOpen3D(mesh);
  FusionMesh out = FromOpen3D(*o3d.SubdivideLoop(iterations));
  out.ComputeVertexNormals();
  return out;
}

}  // namespace hairmvs
