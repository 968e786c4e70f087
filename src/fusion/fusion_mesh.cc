#include <Eigen/Geometry>
#include <algorithm>
#include <numeric>
#include <utility>

#include "src/fusion/fusion_view.h"

namespace hairmvs {
namespace {

int FindRoot(std::vector<int>* parent, int i) {
  while ((*parent)[i] != i) {
    (*parent)[i] = (*parent)[(*parent)[i]];
    i = (*parent)[i];
  }
  return i;
}

}  // namespace

void FusionMesh::ComputeVertexNormals() {
  normals.assign(vertices.size(), Eigen::Vector3d::Zero());
  for (const Eigen::Vector3i& f : faces) {
    // Unnormalised cross product: weights each face by its area.
    const Eigen::Vector3d n =
        (vertices[f[1]] - vertices[f[0]]).cross(vertices[f[2]] - vertices[f[0]]);
    for (int k = 0; k < 3; ++k) normals[f[k]] += n;
  }
  for (Eigen::Vector3d& n : normals) {
    const double norm = n.norm();
    n = norm > 0 ? Eigen::Vector3d(n / norm) : Eigen::Vector3d::Zero();
  }
}

double FusionMesh::MeanEdgeLength() const {
  double sum = 0;
  size_t count = 0;
  for (const Eigen::Vector3i& f : faces) {
    for (int k = 0; k < 3; ++k) {
      sum += (vertices[f[k]] - vertices[f[(k + 1) % 3]]).norm();
      ++count;
    }
  }
  return count > 0 ? sum / count : 0.0;
}

std::vector<std::pair<int, int>> FusionMesh::Edges() const {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(faces.size() * 3);
  for (const Eigen::Vector3i& f : faces) {
    for (int k = 0; k < 3; ++k) edges.push_back(std::minmax(f[k], f[(k + 1) % 3]));
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

int FusionMesh::NumEdges() const { return static_cast<int>(Edges().size()); }

int FusionMesh::EulerCharacteristic() const {
  return static_cast<int>(vertices.size()) - NumEdges() + static_cast<int>(faces.size());
}

std::vector<int> FusionMesh::FaceComponents(int* num_components) const {
  std::vector<int> parent(vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const Eigen::Vector3i& f : faces) {
    for (int k = 1; k < 3; ++k) {
      const int a = FindRoot(&parent, f[0]), b = FindRoot(&parent, f[k]);
      if (a != b) parent[b] = a;
    }
  }
  std::vector<int> label(vertices.size(), -1);
  std::vector<int> component(faces.size());
  int count = 0;
  for (size_t i = 0; i < faces.size(); ++i) {
    const int root = FindRoot(&parent, faces[i][0]);
    if (label[root] < 0) label[root] = count++;
    component[i] = label[root];
  }
  *num_components = count;
  return component;
}

void FusionMesh::KeepFaces(const std::vector<bool>& keep) {
  std::vector<int> new_index(vertices.size(), -1);
  std::vector<Eigen::Vector3i> new_faces;
  std::vector<Eigen::Vector3d> new_vertices;
  for (size_t i = 0; i < faces.size(); ++i) {
    if (!keep[i]) continue;
    Eigen::Vector3i f;
    for (int k = 0; k < 3; ++k) {
      int& idx = new_index[faces[i][k]];
      if (idx < 0) {
        idx = static_cast<int>(new_vertices.size());
        new_vertices.push_back(vertices[faces[i][k]]);
      }
      f[k] = idx;
    }
    new_faces.push_back(f);
  }
  vertices = std::move(new_vertices);
  faces = std::move(new_faces);
  normals.clear();
  colors.clear();
}

}  // namespace hairmvs
