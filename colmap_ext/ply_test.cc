#include "colmap_ext/ply.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <sstream>

#include "colmap_ext/test_util.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace hairmvs {
namespace {

std::vector<FusedPoint> SomePoints(int n) {
  std::vector<FusedPoint> points(n);
  for (int i = 0; i < n; ++i) {
    points[i].xyz = Eigen::Vector3f(i * 0.5f, -1.0f / (i + 1), 5.0f);
    points[i].normal = Eigen::Vector3f(0, 0.6f, -0.8f);
    points[i].rgb[0] = static_cast<uint8_t>(i);
    points[i].rgb[1] = 200;
    points[i].rgb[2] = 7;
    for (int k = 0; k <= i % 3; ++k) points[i].visible_image_idxs.push_back(k * 2 + i % 2);
  }
  return points;
}

void ExpectPointsEqual(const std::vector<FusedPoint>& a, const std::vector<FusedPoint>& b,
                       bool with_vis) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].xyz, b[i].xyz);
    EXPECT_EQ(a[i].normal, b[i].normal);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a[i].rgb[k], b[i].rgb[k]);
    if (with_vis) {
      EXPECT_EQ(a[i].visible_image_idxs, b[i].visible_image_idxs);
    }
  }
}

TEST(FusedPly, ExactColmapLayout) {
  // colmap-formats.md 5: header 232 B for N = 2832, 27 B per vertex; .vis 8 + sum(4 + 4M).
  std::vector<FusedPoint> points(2832);
  for (FusedPoint& p : points) p.visible_image_idxs = {0, 1};
  std::stringstream ply, vis;
  WriteFusedPlyPoints(ply, points);
  WriteFusedVis(vis, points);
  EXPECT_EQ(ply.str().size(), 76696u);
  EXPECT_EQ(vis.str().size(), 33992u);
  EXPECT_EQ(ply.str().find("end_header\n") + 11, 232u);
}

TEST(FusedPly, RoundTripThroughMemory) {
  const std::vector<FusedPoint> points = SomePoints(50);
  std::stringstream ply, vis;
  WriteFusedPlyPoints(ply, points);
  WriteFusedVis(vis, points);
  std::vector<FusedPoint> read = ReadFusedPlyPoints(ply, "mem.ply");
  ReadFusedVis(vis, "mem.ply.vis", &read);
  ExpectPointsEqual(points, read, true);
}

TEST(FusedPly, RoundTripThroughFilesAndEmptyCloud) {
  const std::string dir = testing_util::MakeTestDir("ply");
  const std::vector<FusedPoint> points = SomePoints(9);
  WriteFusedPly(JoinPaths(dir, "fused.ply"), points);
  ExpectPointsEqual(points, ReadFusedPly(JoinPaths(dir, "fused.ply")), true);
  WriteFusedPly(JoinPaths(dir, "empty.ply"), {});
  EXPECT_TRUE(ReadFusedPly(JoinPaths(dir, "empty.ply")).empty());
  EXPECT_EQ(ReadTextFile(JoinPaths(dir, "empty.ply.vis")).size(), 8u);
}

// fused.ply and fused.ply.vis are one unit: a .vis that cannot be written (the disk full)
// leaves the old PLY, not a new one beside an old .vis of another point count.
TEST(FusedPly, FailedVisLeavesTheOldPly) {
  const std::string dir = testing_util::MakeTestDir("ply_unit");
  const std::string path = JoinPaths(dir, "fused.ply");
  WriteFusedPly(path, SomePoints(3));
  const std::string old_ply = ReadTextFile(path), old_vis = ReadTextFile(path + ".vis");
  // 100 points seen in 20 images: a PLY of 2.9 kB and a .vis of 8.4 kB.
  std::vector<FusedPoint> points = SomePoints(100);
  for (FusedPoint& p : points) p.visible_image_idxs.assign(20, 1);
  {
    const testing_util::FileSizeLimit disk_full(4096);
    const std::string message = testing_util::ErrorOf([&] { WriteFusedPly(path, points); });
    EXPECT_NE(message.find(path + ".vis"), std::string::npos) << message;
  }
  // EXPECT_TRUE: a failure does not print kilobytes of binary.
  EXPECT_TRUE(ReadTextFile(path) == old_ply) << "fused.ply was replaced";
  EXPECT_TRUE(ReadTextFile(path + ".vis") == old_vis) << "fused.ply.vis was replaced";
  EXPECT_EQ(testing_util::NumEntriesIn(dir), 2);
}

TEST(FusedPly, ReadsAsciiAndBigEndianWithOtherNames) {
  std::istringstream ascii(
      "ply\nformat ascii 1.0\ncomment hi\nelement vertex 2\nproperty double x\n"
      "property double y\nproperty double z\nproperty uchar r\nproperty uchar g\n"
      "property uchar b\nelement face 0\nproperty list uchar int vertex_indices\n"
      "end_header\n1 2 3 10 20 30\n-1 -2 -3.5 0 0 255\n");
  const std::vector<FusedPoint> a = ReadFusedPlyPoints(ascii, "a.ply");
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[1].xyz, Eigen::Vector3f(-1, -2, -3.5f));
  EXPECT_EQ(a[0].rgb[1], 20);
  EXPECT_EQ(a[1].normal, Eigen::Vector3f::Zero());

  std::string be = "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\n"
                   "property float y\nproperty float z\nend_header\n";
  for (float v : {1.5f, -2.0f, 4.25f}) {
    char bytes[4];
    std::memcpy(bytes, &v, 4);
    be.append({bytes[3], bytes[2], bytes[1], bytes[0]});
  }
  std::istringstream in(be);
  const std::vector<FusedPoint> b = ReadFusedPlyPoints(in, "b.ply");
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].xyz, Eigen::Vector3f(1.5f, -2.0f, 4.25f));
}

TEST(FusedPly, BadInput) {
  const std::vector<FusedPoint> points = SomePoints(5);
  std::stringstream ply, vis;
  WriteFusedPlyPoints(ply, points);
  WriteFusedVis(vis, points);
  const std::string bytes = ply.str();
  {
    std::istringstream in(bytes.substr(0, bytes.size() - 3));
    EXPECT_THROW(ReadFusedPlyPoints(in, "t.ply"), Error);
  }
  {
    std::istringstream in(bytes + "xx");
    EXPECT_THROW(ReadFusedPlyPoints(in, "t.ply"), Error);
  }
  {
    std::istringstream in("solid stl\n");
    try {
      ReadFusedPlyPoints(in, "t.ply");
      ADD_FAILURE();
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("t.ply: not a PLY file"), std::string::npos);
    }
  }
  {
    std::istringstream in("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                          "end_header\n1\n");
    EXPECT_THROW(ReadFusedPlyPoints(in, "t.ply"), Error);  // no y, z
  }
  std::vector<FusedPoint> read = points;
  read.pop_back();  // count mismatch
  std::istringstream vin(vis.str());
  EXPECT_THROW(ReadFusedVis(vin, "t.ply.vis", &read), Error);
  std::vector<FusedPoint> read2 = points;
  std::istringstream vin2(vis.str().substr(0, vis.str().size() - 2));
  EXPECT_THROW(ReadFusedVis(vin2, "t.ply.vis", &read2), Error);
}

TEST(MeshPly, RoundTripWithAndWithoutAttributes) {
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0.5f}};
  mesh.faces = {{0, 1, 2}, {1, 3, 2}};
  for (int variant = 0; variant < 3; ++variant) {
    TriangleMesh m = mesh;
    if (variant >= 1) m.normals.assign(4, Eigen::Vector3f(0, 0, 1));
    if (variant >= 2) m.colors.assign(4, {1, 2, 3});
    std::stringstream ss;
    WriteMeshPly(ss, m);
    EXPECT_NE(ss.str().find("property list uchar int vertex_indices"), std::string::npos);
    const TriangleMesh read = ReadMeshPly(ss, "mesh.ply");
    EXPECT_EQ(read.vertices, m.vertices);
    EXPECT_EQ(read.normals, m.normals);
    EXPECT_EQ(read.colors, m.colors);
    EXPECT_EQ(read.faces, m.faces);
  }
}

TEST(MeshPly, ReadsAsciiDelaunayStyleAndQuads) {
  std::istringstream in(
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_index\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
  const TriangleMesh mesh = ReadMeshPly(in, "d.ply");
  ASSERT_EQ(mesh.faces.size(), 2u);
  EXPECT_EQ(mesh.faces[1], Eigen::Vector3i(0, 2, 3));
  std::istringstream bad(
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n3 0 1 2\n");
  EXPECT_THROW(ReadMeshPly(bad, "bad.ply"), Error);  // face refers to missing vertices
}

// An element's count is a whole number; one without properties holds no data, however many
// rows it claims (reading them one by one would not end).
TEST(MeshPly, ElementCountsAreCheckedAndEmptyElementsSkipped) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\n";
  const std::string body = "end_header\n0 0 0\n1 0 0\n1 1 0\n3 0 1 2\n";
  for (const char* count : {"-1", "3x", "1e3", "99999999999999999999999"}) {
    std::istringstream in(head + "element junk " + count + "\n" + body);
    const std::string error = testing_util::ErrorOf([&] { ReadMeshPly(in, "j.ply"); });
    EXPECT_NE(error.find("j.ply: PLY header line 9: element 'junk' has no valid count"),
              std::string::npos)
        << error;
  }
  std::istringstream empty_element(head + "element junk 18446744073709551615\n" + body);
  EXPECT_EQ(ReadMeshPly(empty_element, "j.ply").faces.size(), 1u);
}

// A NaN or infinite coordinate, or a face index that is not a whole number, is refused with the
// file and the row named: such a vertex passes every comparison and wrecks the nearest-neighbour
// searches of the evaluation and the fusion's grid.
TEST(MeshPly, NonFiniteVerticesAndFractionalIndicesAreRefused) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const auto error_of = [&](const std::string& body) {
    std::istringstream in(head + body);
    return testing_util::ErrorOf([&] { ReadMeshPly(in, "m.ply"); });
  };
  EXPECT_NE(error_of("0 0 0 0 0 1\n1 nan 0 0 0 1\n1 1 0 0 0 1\n3 0 1 2\n")
                .find("m.ply: vertex 1 has a non-finite position"),
            std::string::npos);
  EXPECT_NE(error_of("0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 inf 1\n3 0 1 2\n")
                .find("m.ply: vertex 2 has a non-finite normal"),
            std::string::npos);
  EXPECT_NE(error_of("0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n3 0 1.5 2\n")
                .find("m.ply: face 0 refers to vertex 1.5"),
            std::string::npos);
  std::istringstream points(head + "0 0 0 0 0 1\n1e39 0 0 0 0 1\n1 1 0 0 0 1\n3 0 1 2\n");
  EXPECT_NE(testing_util::ErrorOf([&] { ReadFusedPlyPoints(points, "f.ply"); })
                .find("f.ply: vertex 1 has a non-finite position"),
            std::string::npos);
}

}  // namespace
}  // namespace hairmvs
