#pragma once
// Synthetic MRF problems for tests and benchmarks (fixed seed, no files).

#include <cstdint>

#include "src/mrf/mrf.h"

namespace hairmvs {

// Stereo-like: a smooth true depth (a slanted plane plus a bump, in label units), a data term
// min(0.25 (label - true)^2, 1) plus uniform noise in [0, 0.3), 10% of the pixels with
// pure-noise costs in [0, 1) (as where orientations do not match), and orientation-like weights
// lambda * exp(-|O(p) - O(q)|^2 / (2 * 0.15^2)) (method.md section 2) from a smooth
// orientation field with a discontinuity at x = 0.6 width. No offsets, no truncation.
MrfProblem SyntheticStereoMrfProblem(int width, int height, int num_labels, float lambda,
                                     uint32_t seed);

}  // namespace hairmvs
