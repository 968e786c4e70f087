#pragma once
// COLMAP's dense Mat<float> files (depth maps, normal maps, and our other per-pixel maps such
// as 2-channel orientation maps): ASCII header "W&H&C&" then W*H*C little-endian float32,
// planar (channel-major), nothing after (colmap-formats.md section 2).

#include <istream>
#include <ostream>
#include <string>

#include "src/core/float_map.h"

namespace hairmvs {

// Throws hairmvs::Error naming `path` for a missing file, a malformed header, or a payload
// that is shorter or longer than W*H*C floats.
FloatMap ReadMat(const std::string& path);
FloatMap ReadMat(std::istream& in, const std::string& source);
// Writes atomically (temporary name, then rename).
void WriteMat(const std::string& path, const FloatMap& map);
void WriteMat(std::ostream& out, const FloatMap& map);

}  // namespace hairmvs
