#include "src/fusion/detail_transfer.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include "src/core/logging.h"

namespace hairmvs {

void SmoothDetailOffsets(const FusionMesh& mesh, double weight, std::vector<double>* offsets) {
  const int n = static_cast<int>(offsets->size());
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < n; ++i) {
    if (std::isnan((*offsets)[i])) continue;
    entries.emplace_back(i, i, 1.0);
    rhs[i] = (*offsets)[i];
  }
  for (const auto& [a, b] : mesh.Edges()) {
    entries.emplace_back(a, a, weight);
    entries.emplace_back(b, b, weight);
    entries.emplace_back(a, b, -weight);
    entries.emplace_back(b, a, -weight);
  }
  // A part of the mesh without targets would make the system singular: a pull to 0 too weak
  // to move the others keeps it solvable; its vertices are given NaN back below.
  for (int i = 0; i < n; ++i) entries.emplace_back(i, i, 1e-9);
  Eigen::SparseMatrix<double> system(n, n);
  system.setFromTriplets(entries.begin(), entries.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(system);
  if (solver.info() != Eigen::Success) {
    LOG(WARNING) << "detail: the offsets' system failed to factorise; per-vertex medians kept";
    return;
  }
  const Eigen::VectorXd solved = solver.solve(rhs);
  // The parts of the mesh (FaceComponents) that hold a vertex with a target.
  int num_components = 0;
  const std::vector<int> component = mesh.FaceComponents(&num_components);
  std::vector<bool> has_target(num_components, false);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      if (!std::isnan((*offsets)[mesh.faces[f][k]])) has_target[component[f]] = true;
    }
  }
  std::vector<bool> reached(n, false);
  for (int i = 0; i < n; ++i) reached[i] = !std::isnan((*offsets)[i]);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!has_target[component[f]]) continue;
    for (int k = 0; k < 3; ++k) reached[mesh.faces[f][k]] = true;
  }
  for (int i = 0; i < n; ++i) (*offsets)[i] = reached[i] ? solved[i] : std::nan("");
}

DetailStats TransferDetail(const std::vector<FusionView>& views,
                           const TemplateFusionOptions& options, double cell_m,
                           FusionMesh* mesh) {
  mesh->ComputeVertexNormals();
  const double min_cos = std::cos(options.max_detail_view_angle_deg * M_PI / 180.0);
  const double max_offset = options.max_detail_offset_cells * cell_m;
  std::vector<Eigen::Vector3d> centers;
  for (const FusionView& view : views) centers.push_back(view.Center());
  const int n = static_cast<int>(mesh->vertices.size());
  std::vector<double> offsets(n, std::nan(""));
#pragma omp parallel for schedule(static) num_threads(options.num_threads)
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& v = mesh->vertices[i];
    const Eigen::Vector3d& normal = mesh->normals[i];
    if (normal.squaredNorm() < 0.5) continue;
    std::vector<double> s;
    for (size_t j = 0; j < views.size(); ++j) {
      if (normal.dot((centers[j] - v).normalized()) < min_cos) continue;
      double z, d;
      if (!views[j].DepthOnRay(v, &z, &d)) continue;
      const double offset = (views[j].SurfaceOnRay(v, z, d) - v).dot(normal);
      if (std::abs(offset) <= max_offset) s.push_back(offset);
    }
    if (s.empty()) continue;
    const size_t mid = s.size() / 2;
    std::nth_element(s.begin(), s.begin() + mid, s.end());
    double median = s[mid];
    if (s.size() % 2 == 0) median = 0.5 * (median + *std::max_element(s.begin(), s.begin() + mid));
    offsets[i] = median;
  }
  if (options.detail_smoothness_weight > 0) {
    SmoothDetailOffsets(*mesh, options.detail_smoothness_weight, &offsets);
  }
  DetailStats stats;
  std::vector<double> magnitudes;
  for (int i = 0; i < n; ++i) {
    if (std::isnan(offsets[i])) continue;
    mesh->vertices[i] += offsets[i] * mesh->normals[i];
    magnitudes.push_back(std::abs(offsets[i]));
  }
  stats.num_vertices_with_detail = static_cast<int>(magnitudes.size());
  if (!magnitudes.empty()) {
    std::nth_element(magnitudes.begin(), magnitudes.begin() + magnitudes.size() / 2,
                     magnitudes.end());
    stats.median_abs_offset_m = magnitudes[magnitudes.size() / 2];
  }
  mesh->ComputeVertexNormals();
  return stats;
}

void ColorizeMesh(const std::vector<FusionView>& views, const TemplateFusionOptions& options,
                  FusionMesh* mesh) {
  if (mesh->normals.size() != mesh->vertices.size()) mesh->ComputeVertexNormals();
  std::vector<Eigen::Vector3d> centers;
  for (const FusionView& view : views) centers.push_back(view.Center());
  const int n = static_cast<int>(mesh->vertices.size());
  mesh->colors.assign(n, {128, 128, 128});
#pragma omp parallel for schedule(static) num_threads(options.num_threads)
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& v = mesh->vertices[i];
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double weight = 0;
    for (size_t j = 0; j < views.size(); ++j) {
      if (views[j].rgb.Channels() != 3) continue;
      const double cos_angle = mesh->normals[i].dot((centers[j] - v).normalized());
      if (cos_angle <= 0) continue;
      int col, row;
      double z;
      if (!views[j].Project(v, &col, &row, &z)) continue;
      const float d = views[j].depth.At(row, col);
      if (!(d > 0) || std::abs(d - z) > options.visibility_depth_tolerance * z) continue;
      for (int k = 0; k < 3; ++k) sum[k] += cos_angle * views[j].rgb.At(row, col, k);
      weight += cos_angle;
    }
    if (weight <= 0) continue;
    for (int k = 0; k < 3; ++k) {
      mesh->colors[i][k] =
          static_cast<uint8_t>(std::lround(std::clamp(sum[k] / weight, 0.0, 1.0) * 255.0));
    }
  }
}

}  // namespace hairmvs
