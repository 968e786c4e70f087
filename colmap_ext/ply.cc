#include "colmap_ext/ply.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace hairmvs {

namespace {

// ---------------------------------------------------------------------------------------------
// A small generic PLY reader: header, then every element's rows handed to a callback.

enum class PlyType { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };
enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

bool ParsePlyType(const std::string& name, PlyType* type) {
  static const std::map<std::string, PlyType> kTypes = {
      {"char", PlyType::kInt8},     {"int8", PlyType::kInt8},
      {"uchar", PlyType::kUInt8},   {"uint8", PlyType::kUInt8},
      {"short", PlyType::kInt16},   {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUInt16}, {"uint16", PlyType::kUInt16},
      {"int", PlyType::kInt32},     {"int32", PlyType::kInt32},
      {"uint", PlyType::kUInt32},   {"uint32", PlyType::kUInt32},
      {"float", PlyType::kFloat32}, {"float32", PlyType::kFloat32},
      {"double", PlyType::kFloat64}, {"float64", PlyType::kFloat64}};
  const auto it = kTypes.find(name);
  if (it == kTypes.end()) return false;
  *type = it->second;
  return true;
}

int PlyTypeSize(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUInt8: return 1;
    case PlyType::kInt16:
    case PlyType::kUInt16: return 2;
    case PlyType::kInt32:
    case PlyType::kUInt32:
    case PlyType::kFloat32: return 4;
    case PlyType::kFloat64: return 8;
  }
  return 0;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool is_list = false;
  PlyType count_type = PlyType::kUInt8;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;

  int Find(const std::string& property) const {
    for (size_t i = 0; i < properties.size(); ++i) {
      if (properties[i].name == property) return static_cast<int>(i);
    }
    return -1;
  }
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
};

PlyHeader ReadPlyHeader(std::istream& in, const std::string& source) {
  PlyHeader header;
  std::string line;
  THROW_IF(!std::getline(in, line) || StripWhitespace(line) != "ply",
           source << ": not a PLY file (first line is not 'ply')");
  bool have_format = false;
  int line_number = 1;
  while (true) {
    THROW_IF(!std::getline(in, line), source << ": PLY header has no end_header");
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ss(line);
    std::string keyword;
    ss >> keyword;
    if (keyword == "end_header") break;
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    const std::string where = source + ": PLY header line " + std::to_string(line_number);
    if (keyword == "format") {
      std::string format, version;
      ss >> format >> version;
      if (format == "ascii") {
        header.format = PlyFormat::kAscii;
      } else if (format == "binary_little_endian") {
        header.format = PlyFormat::kBinaryLittleEndian;
      } else if (format == "binary_big_endian") {
        header.format = PlyFormat::kBinaryBigEndian;
      } else {
        HAIRMVS_THROW(where << ": unknown format '" << format << "'");
      }
      have_format = true;
    } else if (keyword == "element") {
      PlyElement element;
      std::string count;
      THROW_IF(!(ss >> element.name >> count), where << ": malformed element line");
      // Parsed strictly: `>>` into an unsigned count would take "-1" as 2^64 - 1.
      const char* count_end = count.data() + count.size();
      const auto parsed = std::from_chars(count.data(), count_end, element.count);
      THROW_IF(parsed.ec != std::errc() || parsed.ptr != count_end,
               where << ": element '" << element.name << "' has no valid count ('" << count
                     << "')");
      header.elements.push_back(element);
    } else if (keyword == "property") {
      THROW_IF(header.elements.empty(), where << ": property before any element");
      PlyProperty property;
      std::string type;
      ss >> type;
      if (type == "list") {
        std::string count_type, item_type;
        ss >> count_type >> item_type >> property.name;
        property.is_list = true;
        THROW_IF(!ParsePlyType(count_type, &property.count_type) ||
                     !ParsePlyType(item_type, &property.type) || property.name.empty(),
                 where << ": malformed list property '" << line << "'");
      } else {
        ss >> property.name;
        THROW_IF(!ParsePlyType(type, &property.type) || property.name.empty(),
                 where << ": unknown property type in '" << line << "'");
      }
      header.elements.back().properties.push_back(property);
    } else {
      HAIRMVS_THROW(where << ": unknown header keyword '" << keyword << "'");
    }
  }
  THROW_IF(!have_format, source << ": PLY header has no format line");
  return header;
}

class PlyValueReader {
 public:
  PlyValueReader(std::istream& in, PlyFormat format, std::string source)
      : in_(in), format_(format), source_(std::move(source)) {}

  double Read(PlyType type, const char* element) {
    if (format_ == PlyFormat::kAscii) {
      std::string token;
      THROW_IF(!(in_ >> token), source_ << ": truncated PLY data in element '" << element << "'");
      errno = 0;
      char* end = nullptr;
      const double value = std::strtod(token.c_str(), &end);
      THROW_IF(end != token.c_str() + token.size(),
               source_ << ": cannot parse '" << token << "' in element '" << element << "'");
      return value;
    }
    const int size = PlyTypeSize(type);
    char bytes[8];
    in_.read(bytes, size);
    THROW_IF(in_.gcount() != size,
             source_ << ": truncated PLY data in element '" << element << "'");
    if (format_ == PlyFormat::kBinaryBigEndian) std::reverse(bytes, bytes + size);
    switch (type) {
      case PlyType::kInt8: return Get<int8_t>(bytes);
      case PlyType::kUInt8: return Get<uint8_t>(bytes);
      case PlyType::kInt16: return Get<int16_t>(bytes);
      case PlyType::kUInt16: return Get<uint16_t>(bytes);
      case PlyType::kInt32: return Get<int32_t>(bytes);
      case PlyType::kUInt32: return Get<uint32_t>(bytes);
      case PlyType::kFloat32: return Get<float>(bytes);
      case PlyType::kFloat64: return Get<double>(bytes);
    }
    return 0.0;
  }

 private:
  template <typename T>
  static double Get(const char* bytes) {
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return static_cast<double>(value);
  }

  std::istream& in_;
  PlyFormat format_;
  std::string source_;
};

using RowCallback = std::function<void(const PlyElement& element, uint64_t row,
                                       const std::vector<double>& scalars,
                                       const std::vector<std::vector<double>>& lists)>;

// scalars[i] / lists[i] are indexed by property index (the other vector's entry is unused).
void ReadPlyBody(std::istream& in, const PlyHeader& header, const std::string& source,
                 const RowCallback& on_row) {
  PlyValueReader reader(in, header.format, source);
  for (const PlyElement& element : header.elements) {
    // An element without properties has no data: its rows, however many, take no bytes (and
    // counting through 2^64 of them would not end).
    if (element.properties.empty()) continue;
    std::vector<double> scalars(element.properties.size(), 0.0);
    std::vector<std::vector<double>> lists(element.properties.size());
    for (uint64_t row = 0; row < element.count; ++row) {
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (!property.is_list) {
          scalars[p] = reader.Read(property.type, element.name.c_str());
          continue;
        }
        const double count = reader.Read(property.count_type, element.name.c_str());
        THROW_IF(count < 0 || count > (1 << 20),
                 source << ": invalid list length " << count << " in element '" << element.name
                        << "'");
        lists[p].resize(static_cast<size_t>(count));
        for (double& v : lists[p]) v = reader.Read(property.type, element.name.c_str());
      }
      on_row(element, row, scalars, lists);
    }
  }
  if (header.format == PlyFormat::kAscii) {
    std::string token;
    THROW_IF(in >> token, source << ": unexpected data after the last PLY element");
  } else {
    THROW_IF(in.peek() != std::char_traits<char>::eof(),
             source << ": unexpected bytes after the last PLY element (oversized file)");
  }
}

const PlyElement* FindElement(const PlyHeader& header, const std::string& name) {
  for (const PlyElement& element : header.elements) {
    if (element.name == name) return &element;
  }
  return nullptr;
}

// Index of the first of `names` present in `element`, or -1.
int FindAny(const PlyElement& element, std::initializer_list<const char*> names) {
  for (const char* name : names) {
    const int index = element.Find(name);
    if (index >= 0) return index;
  }
  return -1;
}

struct VertexLayout {
  int xyz[3] = {-1, -1, -1};
  int normal[3] = {-1, -1, -1};
  int rgb[3] = {-1, -1, -1};
  bool has_normals = false;
  bool has_colors = false;
};

VertexLayout FindVertexLayout(const PlyElement& vertex, const std::string& source) {
  VertexLayout layout;
  const char* kXyz[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    layout.xyz[k] = vertex.Find(kXyz[k]);
    THROW_IF(layout.xyz[k] < 0 || vertex.properties[layout.xyz[k]].is_list,
             source << ": PLY vertex element has no scalar property '" << kXyz[k] << "'");
  }
  layout.normal[0] = vertex.Find("nx");
  layout.normal[1] = vertex.Find("ny");
  layout.normal[2] = vertex.Find("nz");
  layout.has_normals = layout.normal[0] >= 0 && layout.normal[1] >= 0 && layout.normal[2] >= 0;
  // Colour names COLMAP's ReadPly accepts.
  layout.rgb[0] = FindAny(vertex, {"red", "r", "diffuse_red", "ambient_red", "specular_red"});
  layout.rgb[1] =
      FindAny(vertex, {"green", "g", "diffuse_green", "ambient_green", "specular_green"});
  layout.rgb[2] = FindAny(vertex, {"blue", "b", "diffuse_blue", "ambient_blue", "specular_blue"});
  layout.has_colors = layout.rgb[0] >= 0 && layout.rgb[1] >= 0 && layout.rgb[2] >= 0;
  return layout;
}

// The three properties `index` of a vertex row, refused unless finite: a NaN or infinite point
// would pass every test that compares it and wreck the nearest-neighbour searches and the
// Poisson grid that take it.
Eigen::Vector3f FiniteVector(const int index[3], const std::vector<double>& s, uint64_t row,
                             const char* what, const std::string& source) {
  const Eigen::Vector3f v = Eigen::Vector3d(s[index[0]], s[index[1]], s[index[2]]).cast<float>();
  THROW_IF(!v.allFinite(), source << ": vertex " << row << " has a non-finite " << what << " ("
                                  << v.x() << ", " << v.y() << ", " << v.z() << ")");
  return v;
}

uint8_t ToByte(double v) {
  return static_cast<uint8_t>(std::clamp(std::lround(v), 0L, 255L));
}

template <typename T>
void WriteLE(std::ostream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));  // little-endian host
}

template <typename T>
T ReadLE(std::istream& in, const std::string& source, const char* what) {
  T value;
  in.read(reinterpret_cast<char*>(&value), sizeof(T));
  THROW_IF(in.gcount() != static_cast<std::streamsize>(sizeof(T)),
           source << ": truncated file while reading " << what);
  return value;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Fused points.

void WriteFusedPlyPoints(std::ostream& out, const std::vector<FusedPoint>& points) {
  // Byte for byte COLMAP's WriteBinaryPlyPoints header (232 bytes for N = 2832).
  out << "ply\n"
      << "format binary_little_endian 1.0\n"
      << "element vertex " << points.size() << "\n"
      << "property float x\n"
      << "property float y\n"
      << "property float z\n"
      << "property float nx\n"
      << "property float ny\n"
      << "property float nz\n"
      << "property uchar red\n"
      << "property uchar green\n"
      << "property uchar blue\n"
      << "end_header\n";
  for (const FusedPoint& p : points) {
    for (int k = 0; k < 3; ++k) WriteLE<float>(out, p.xyz[k]);
    for (int k = 0; k < 3; ++k) WriteLE<float>(out, p.normal[k]);
    for (int k = 0; k < 3; ++k) WriteLE<uint8_t>(out, p.rgb[k]);
  }
}

void WriteFusedVis(std::ostream& out, const std::vector<FusedPoint>& points) {
  WriteLE<uint64_t>(out, points.size());
  for (const FusedPoint& p : points) {
    WriteLE<uint32_t>(out, static_cast<uint32_t>(p.visible_image_idxs.size()));
    for (uint32_t idx : p.visible_image_idxs) WriteLE<uint32_t>(out, idx);
  }
}

void WriteFusedPly(const std::string& ply_path, const std::vector<FusedPoint>& points) {
  // One unit: COLMAP's mesher CHECK-fails on a .vis of another point count than the PLY's.
  // The .ply last, marking the pair whole: a run stopped between the renames leaves no
  // fused.ply rather than a new one beside an old .vis of another point count (which `colmap
  // delaunay_mesher --input_type dense` reads with it).
  WriteFilesAtomically(
      {{ply_path + ".vis", [&](std::ostream& out) { WriteFusedVis(out, points); }},
       {ply_path, [&](std::ostream& out) { WriteFusedPlyPoints(out, points); }}},
      /*last_marks_complete=*/true);
}

std::vector<FusedPoint> ReadFusedPlyPoints(std::istream& in, const std::string& source) {
  const PlyHeader header = ReadPlyHeader(in, source);
  const PlyElement* vertex = FindElement(header, "vertex");
  THROW_IF(vertex == nullptr, source << ": PLY file has no vertex element");
  const VertexLayout layout = FindVertexLayout(*vertex, source);
  std::vector<FusedPoint> points;
  points.reserve(static_cast<size_t>(std::min<uint64_t>(vertex->count, 1u << 24)));
  ReadPlyBody(in, header, source,
              [&](const PlyElement& element, uint64_t row, const std::vector<double>& s,
                  const std::vector<std::vector<double>>&) {
                if (&element != vertex) return;
                FusedPoint p;
                p.xyz = FiniteVector(layout.xyz, s, row, "position", source);
                if (layout.has_normals) {
                  p.normal = FiniteVector(layout.normal, s, row, "normal", source);
                }
                if (layout.has_colors) {
                  for (int k = 0; k < 3; ++k) p.rgb[k] = ToByte(s[layout.rgb[k]]);
                }
                points.push_back(std::move(p));
              });
  return points;
}

void ReadFusedVis(std::istream& in, const std::string& source, std::vector<FusedPoint>* points) {
  const uint64_t num_points = ReadLE<uint64_t>(in, source, "the number of points");
  THROW_IF(num_points != points->size(),
           source << ": visibility file lists " << num_points << " points, the PLY has "
                  << points->size());
  for (FusedPoint& p : *points) {
    const uint32_t num_visible = ReadLE<uint32_t>(in, source, "a visibility count");
    p.visible_image_idxs.clear();
    p.visible_image_idxs.reserve(std::min<uint32_t>(num_visible, 1u << 16));
    for (uint32_t k = 0; k < num_visible; ++k) {
      p.visible_image_idxs.push_back(ReadLE<uint32_t>(in, source, "an image index"));
    }
  }
  THROW_IF(in.peek() != std::char_traits<char>::eof(),
           source << ": unexpected bytes after the last visibility record (oversized file)");
}

std::vector<FusedPoint> ReadFusedPly(const std::string& ply_path) {
  RequireFile(ply_path, "PLY file");
  std::ifstream in(ply_path, std::ios::binary);
  THROW_IF(!in, "Cannot open " << ply_path);
  std::vector<FusedPoint> points = ReadFusedPlyPoints(in, ply_path);
  const std::string vis_path = ply_path + ".vis";
  if (ExistsFile(vis_path)) {
    std::ifstream vis(vis_path, std::ios::binary);
    THROW_IF(!vis, "Cannot open " << vis_path);
    ReadFusedVis(vis, vis_path, &points);
  }
  return points;
}

// ---------------------------------------------------------------------------------------------
// Meshes.

void WriteMeshPly(std::ostream& out, const TriangleMesh& mesh) {
  const bool has_normals = !mesh.normals.empty();
  const bool has_colors = !mesh.colors.empty();
  CHECK(!has_normals || mesh.normals.size() == mesh.vertices.size());
  CHECK(!has_colors || mesh.colors.size() == mesh.vertices.size());
  out << "ply\n"
      << "format binary_little_endian 1.0\n"
      << "element vertex " << mesh.vertices.size() << "\n"
      << "property float x\n"
      << "property float y\n"
      << "property float z\n";
  if (has_normals) out << "property float nx\nproperty float ny\nproperty float nz\n";
  if (has_colors) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out << "element face " << mesh.faces.size() << "\n"
      << "property list uchar int vertex_indices\n"
      << "end_header\n";
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) WriteLE<float>(out, mesh.vertices[i][k]);
    if (has_normals) {
      for (int k = 0; k < 3; ++k) WriteLE<float>(out, mesh.normals[i][k]);
    }
    if (has_colors) {
      for (int k = 0; k < 3; ++k) WriteLE<uint8_t>(out, mesh.colors[i][k]);
    }
  }
  for (const Eigen::Vector3i& face : mesh.faces) {
    WriteLE<uint8_t>(out, 3);
    for (int k = 0; k < 3; ++k) WriteLE<int32_t>(out, face[k]);
  }
}

void WriteMeshPly(const std::string& path, const TriangleMesh& mesh) {
  WriteFileAtomically(path, [&](std::ostream& out) { WriteMeshPly(out, mesh); });
}

TriangleMesh ReadMeshPly(std::istream& in, const std::string& source) {
  const PlyHeader header = ReadPlyHeader(in, source);
  const PlyElement* vertex = FindElement(header, "vertex");
  THROW_IF(vertex == nullptr, source << ": PLY file has no vertex element");
  const VertexLayout layout = FindVertexLayout(*vertex, source);
  const PlyElement* face = FindElement(header, "face");
  int face_property = -1;
  if (face != nullptr) {
    face_property = FindAny(*face, {"vertex_indices", "vertex_index"});
    THROW_IF(face_property < 0 || !face->properties[face_property].is_list,
             source << ": PLY face element has no list property vertex_indices/vertex_index");
  }
  TriangleMesh mesh;
  const uint64_t num_vertices = vertex->count;
  ReadPlyBody(in, header, source,
              [&](const PlyElement& element, uint64_t row, const std::vector<double>& s,
                  const std::vector<std::vector<double>>& lists) {
                if (&element == vertex) {
                  mesh.vertices.push_back(FiniteVector(layout.xyz, s, row, "position", source));
                  if (layout.has_normals) {
                    mesh.normals.push_back(FiniteVector(layout.normal, s, row, "normal", source));
                  }
                  if (layout.has_colors) {
                    mesh.colors.push_back({ToByte(s[layout.rgb[0]]), ToByte(s[layout.rgb[1]]),
                                           ToByte(s[layout.rgb[2]])});
                  }
                } else if (&element == face) {
                  const std::vector<double>& idx = lists[face_property];
                  THROW_IF(idx.size() < 3, source << ": face " << row << " has " << idx.size()
                                                  << " vertices");
                  for (double v : idx) {
                    THROW_IF(!(v >= 0 && v < static_cast<double>(num_vertices)) ||
                                 v != std::floor(v),
                             source << ": face " << row << " refers to vertex " << v << " of "
                                    << num_vertices);
                  }
                  // Fan triangulation of polygons.
                  for (size_t k = 1; k + 1 < idx.size(); ++k) {
                    mesh.faces.emplace_back(static_cast<int>(idx[0]), static_cast<int>(idx[k]),
                                            static_cast<int>(idx[k + 1]));
                  }
                }
              });
  return mesh;
}

TriangleMesh ReadMeshPly(const std::string& path) {
  RequireFile(path, "PLY mesh");
  std::ifstream in(path, std::ios::binary);
  THROW_IF(!in, "Cannot open " << path);
  return ReadMeshPly(in, path);
}

}  // namespace hairmvs
