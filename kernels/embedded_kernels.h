#pragma once
// The OpenCL C sources of kernels/, embedded at build time (cmake/EmbedKernels.cmake).

#include <map>
#include <string>

namespace hairmvs {

// File name (e.g. "orientation.cl", "common.clh") -> source text.
const std::map<std::string, std::string>& EmbeddedKernelSources();

}  // namespace hairmvs
