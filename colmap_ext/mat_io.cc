#include "colmap_ext/mat_io.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iomanip>
#include <fstream>
#include <limits>

#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace hairmvs {

static_assert(sizeof(float) == 4, "float32 expected");

namespace {

// The header, read field by field as COLMAP does: W & H & C &; no newline may follow.
MatShape ReadMatHeader(std::istream& in, const std::string& source) {
  long width = 0, height = 0, channels = 0;
  char sep1 = 0, sep2 = 0, sep3 = 0;
  in >> width >> sep1 >> height >> sep2 >> channels >> sep3;
  THROW_IF(!in || sep1 != '&' || sep2 != '&' || sep3 != '&',
           source << ": not a COLMAP Mat file (expected a header \"W&H&C&\")");
  // Cost volumes have a channel per depth label (hundreds); more than 4096 is a broken header.
  THROW_IF(width <= 0 || height <= 0 || channels <= 0 || width > (1 << 16) ||
               height > (1 << 16) || channels > 4096,
           source << ": invalid Mat dimensions " << width << "x" << height << "x" << channels);
  return {static_cast<int>(width), static_cast<int>(height), static_cast<int>(channels)};
}

// The payload's size in bytes, and the errors for a payload of another size.
std::streamsize PayloadBytes(const MatShape& shape) {
  return static_cast<std::streamsize>(shape.width) * shape.height * shape.channels *
         static_cast<std::streamsize>(sizeof(float));
}
void RequirePayloadBytes(const MatShape& shape, std::streamsize found, bool more_after,
                         const std::string& source) {
  THROW_IF(found < PayloadBytes(shape),
           source << ": truncated Mat file: expected " << PayloadBytes(shape)
                  << " bytes of data for " << shape.width << "x" << shape.height << "x"
                  << shape.channels << ", found " << found);
  THROW_IF(more_after, source << ": Mat file has bytes after its " << shape.width << "x"
                              << shape.height << "x" << shape.channels << " payload");
}

std::ifstream OpenMat(const std::string& path) {
  RequireFile(path, "Mat file");
  std::ifstream in(path, std::ios::binary);
  THROW_IF(!in, "Cannot open " << path);
  return in;
}

// The header of the file `in` opened at `path`, checked against the file's size; `in` is left
// at the payload.
MatShape ReadMatHeaderCheckedAgainstFileSize(std::ifstream& in, const std::string& path) {
  const MatShape shape = ReadMatHeader(in, path);
  const std::streamsize header_bytes = in.tellg();
  in.seekg(0, std::ios::end);
  const std::streamsize payload = static_cast<std::streamsize>(in.tellg()) - header_bytes;
  RequirePayloadBytes(shape, std::min(payload, PayloadBytes(shape)),
                      payload > PayloadBytes(shape), path);
  in.seekg(header_bytes);
  return shape;
}

// W*H*C floats from `in`, which is at the payload.
FloatMap ReadMatPayload(std::istream& in, const MatShape& shape, const std::string& source) {
  FloatMap map(shape.width, shape.height, shape.channels);
  in.read(reinterpret_cast<char*>(map.Data().data()), PayloadBytes(shape));
  // Before peek(), which resets gcount().
  const std::streamsize found = in.gcount();
  RequirePayloadBytes(shape, found,
                      found == PayloadBytes(shape) && in.peek() != std::char_traits<char>::eof(),
                      source);
  // COLMAP's maps hold finite numbers (0 where a pixel has no depth or normal). An infinite
  // depth or a NaN normal would pass the tests that compare it (d > 0, |n|^2 < 0.5 is false)
  // and reach the fusion's grid and the evaluation's searches.
  const std::vector<float>& values = map.Data();
  const auto bad = std::find_if(values.begin(), values.end(),
                                [](float v) { return !std::isfinite(v); });
  if (bad != values.end()) {
    const size_t i = static_cast<size_t>(bad - values.begin());
    const size_t plane = static_cast<size_t>(shape.width) * shape.height;
    HAIRMVS_THROW(source << ": Mat file holds a non-finite value (" << *bad << ") at pixel ("
                         << i % plane % shape.width << ", " << i % plane / shape.width
                         << "), channel " << i / plane);
  }
  return map;
}

}  // namespace

FloatMap ReadMat(std::istream& in, const std::string& source) {
  return ReadMatPayload(in, ReadMatHeader(in, source), source);
}

FloatMap ReadMat(const std::string& path) {
  std::ifstream in = OpenMat(path);
  // The size first: a corrupt header in a short file is "truncated", not an allocation of the
  // terabytes it announces.
  const MatShape shape = ReadMatHeaderCheckedAgainstFileSize(in, path);
  return ReadMatPayload(in, shape, path);
}

MatShape ReadMatShape(const std::string& path) {
  std::ifstream in = OpenMat(path);
  return ReadMatHeaderCheckedAgainstFileSize(in, path);
}

void WriteMat(std::ostream& out, const FloatMap& map) {
  CHECK(!map.Empty());
  out << map.Width() << "&" << map.Height() << "&" << map.Channels() << "&";
  out.write(reinterpret_cast<const char*>(map.Data().data()),
            static_cast<std::streamsize>(map.Data().size() * sizeof(float)));
}

void WriteMat(const std::string& path, const FloatMap& map) {
  WriteFileAtomically(path, [&map](std::ostream& out) { WriteMat(out, map); });
}

CostVolume ReadCostVolume(const std::string& path, const std::string& depths_path) {
  CostVolume volume;
  volume.cost = ReadMat(path);
  RequireFile(depths_path, "label depths of " + path);
  const std::vector<std::string> lines = ReadLines(depths_path);
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string line = StripWhitespace(lines[i]);
    if (line.empty() || line[0] == '#') continue;
    char* end = nullptr;
    const double depth = std::strtod(line.c_str(), &end);
    THROW_IF(end == line.c_str() || *end != '\0' || !(depth > 0) || !std::isfinite(depth),
             depths_path << ":" << i + 1 << ": not a positive depth: '" << line << "'");
    // The labels' depths run one way (the evaluation interpolates between neighbours).
    const std::vector<double>& d = volume.label_depths;
    if (!d.empty()) {
      const bool increasing = d.size() < 2 ? depth > d.back() : d.back() > d[d.size() - 2];
      THROW_IF(depth == d.back() || (depth > d.back()) != increasing,
               depths_path << ":" << i + 1 << ": the label depths must run strictly one way; "
                           << line << " follows " << d.back());
    }
    volume.label_depths.push_back(depth);
  }
  THROW_IF(static_cast<int>(volume.label_depths.size()) != volume.cost.Channels(),
           depths_path << ": " << volume.label_depths.size() << " depths for the "
                       << volume.cost.Channels() << " labels of " << path);
  return volume;
}

void WriteCostVolume(const std::string& path, const std::string& depths_path,
                     const CostVolume& volume) {
  CHECK_EQ(static_cast<int>(volume.label_depths.size()), volume.cost.Channels());
  // One unit: ReadCostVolume refuses a Mat beside depths of another number of labels.
  WriteFilesAtomically(
      {{path, [&volume](std::ostream& out) { WriteMat(out, volume.cost); }},
       {depths_path,
        [&volume](std::ostream& out) {
          out << "# depth (m) of each label (channel) of the cost volume, one per line\n"
              << std::setprecision(9);
          for (const double depth : volume.label_depths) out << depth << "\n";
        },
        false}});
}

}  // namespace hairmvs
