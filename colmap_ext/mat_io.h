#pragma once
// COLMAP's dense Mat<float> files (depth maps, normal maps, and our other per-pixel maps such
// as 2-channel orientation maps): ASCII header "W&H&C&" then W*H*C little-endian float32,
// planar (channel-major), nothing after (colmap-formats.md section 2).

#include <istream>
#include <ostream>
#include <string>
#include <vector>

#include "src/core/float_map.h"

namespace hairmvs {

// Throws hairmvs::Error naming `path` for a missing file, a malformed header, or a payload
// that is shorter or longer than W*H*C floats (from a path, checked against the file's size
// before the map is allocated).
FloatMap ReadMat(const std::string& path);
FloatMap ReadMat(std::istream& in, const std::string& source);
// The dimensions of the Mat file at `path`, from its header, checked against the file's size:
// it throws as ReadMat would, but without reading the payload (to tell whether cached maps are
// usable without loading them).
struct MatShape {
  int width = 0;
  int height = 0;
  int channels = 0;
};
MatShape ReadMatShape(const std::string& path);
// Writes atomically (temporary name, then rename).
void WriteMat(const std::string& path, const FloatMap& map);
void WriteMat(std::ostream& out, const FloatMap& map);

// A depth-label cost volume: a Mat with one channel per label ([label][row][col]) at
// `path`, and the labels' depths in metres, one per line ('#' lines are comments), at
// `depths_path`. hairmvs writes stereo/cost_volumes/<name>.coarse.bin and .coarse.depths.txt.
struct CostVolume {
  FloatMap cost;
  std::vector<double> label_depths;
};
// Throws hairmvs::Error naming the file for: a missing file, a malformed Mat, a line that is
// not a positive number, or a number of depths other than the Mat's channels.
CostVolume ReadCostVolume(const std::string& path, const std::string& depths_path);
// Writes both files as one unit (WriteFilesAtomically). CHECKs that there is one depth per
// channel.
void WriteCostVolume(const std::string& path, const std::string& depths_path,
                     const CostVolume& volume);

}  // namespace hairmvs
