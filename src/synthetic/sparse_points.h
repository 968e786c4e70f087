#pragma once
// The sparse model of a synthetic set: the true PINHOLE camera and poses, and 3D points
// sampled on the visible hair and head surfaces (back-projected true depths), each kept when
// the true depth maps say it is visible in at least 2 views, with its 2D observations, so that
// COLMAP's __auto__ source-view selection and depth ranges work on the set.

#include <cstdint>
#include <vector>

#include "colmap_ext/reconstruction.h"
#include "src/synthetic/camera_rig.h"
#include "src/synthetic/renderer.h"

namespace hairmvs {

// All views share one camera (id 1); image ids are 1..n in the order of `views`.
// A point is observed in view j when it projects inside the image in front of the camera and
// the true depth of the pixel it falls in is within two pixel footprints of its own depth.
Reconstruction MakeSparseModel(const std::vector<SyntheticView>& views,
                               const std::vector<RenderedView>& renders, int samples_per_view,
                               uint64_t seed);

}  // namespace hairmvs
