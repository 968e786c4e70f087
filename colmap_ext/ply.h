#pragma once
// COLMAP's dense outputs as PLY: fused point clouds (fused.ply + fused.ply.vis, exactly as
// `colmap stereo_fusion` writes them) and triangle meshes (as `colmap poisson_mesher` writes
// them). colmap-formats.md section 5.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <istream>
#include <ostream>
#include <string>
#include <vector>

namespace hairmvs {

struct FusedPoint {
  Eigen::Vector3f xyz = Eigen::Vector3f::Zero();
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  // world frame, unit
  uint8_t rgb[3] = {0, 0, 0};
  // COLMAP image_idx values: the order of the records in sparse/images.* (reconstruction.h).
  std::vector<uint32_t> visible_image_idxs;
};

// Writes `ply_path` (binary little-endian, x y z nx ny nz float, red green blue uchar: 27
// bytes per vertex, COLMAP's exact header) and `ply_path` + ".vis" (uint64 N, then per point
// uint32 M and M uint32 image_idx), as one unit (WriteFilesAtomically, the .ply marking it
// complete): if either write fails, both old files are left as they were; once both are
// written the old .ply is removed first, so that a run stopped between the renames leaves
// no .ply (to be made again), never a new one beside the old .vis.
void WriteFusedPly(const std::string& ply_path, const std::vector<FusedPoint>& points);
// Reads any PLY whose vertex element has x y z (float or double), optionally nx ny nz and
// red/green/blue (or r/g/b, diffuse_red...) in ascii, binary_little_endian or
// binary_big_endian; reads `ply_path` + ".vis" when it exists (its point count must match).
// Throws hairmvs::Error naming the file and the problem.
std::vector<FusedPoint> ReadFusedPly(const std::string& ply_path);

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Vector3f> normals;              // empty or one per vertex
  std::vector<std::array<uint8_t, 3>> colors;         // empty or one per vertex
  std::vector<Eigen::Vector3i> faces;                 // vertex indices
};

// Binary little-endian, faces as `property list uchar int vertex_indices` like COLMAP's
// Poisson mesher; normals and colours written when non-empty. Atomic.
void WriteMeshPly(const std::string& path, const TriangleMesh& mesh);
// Ascii or binary (either endianness); faces from `vertex_indices` or `vertex_index`
// (Delaunay mesher spelling); polygons with more than 3 vertices are fanned into triangles.
TriangleMesh ReadMeshPly(const std::string& path);

// Stream versions (tests round-trip through memory). `source` names the stream in errors.
void WriteFusedPlyPoints(std::ostream& out, const std::vector<FusedPoint>& points);
void WriteFusedVis(std::ostream& out, const std::vector<FusedPoint>& points);
std::vector<FusedPoint> ReadFusedPlyPoints(std::istream& in, const std::string& source);
void ReadFusedVis(std::istream& in, const std::string& source, std::vector<FusedPoint>* points);
void WriteMeshPly(std::ostream& out, const TriangleMesh& mesh);
TriangleMesh ReadMeshPly(std::istream& in, const std::string& source);

}  // namespace hairmvs
