#pragma once
// Semi-global matching (Hirschmueller 2008) on the MRF of src/mrf/mrf.h: for each of 4 or 8
// scanline directions r, the 1-D dynamic programme
//   L_r(p, b) = C(p, b) + min_a [L_r(p - r, a) + V(a, b)] - min_a L_r(p - r, a)
// with the MRF's own pairwise term V(a, b) = w * min((value(p-r, a) - value(p, b))^2, trunc)
// then label(p) = argmin_b sum_r L_r(p, b). The inner minimum is found in O(L) per pixel and
// direction with the lower envelope of parabolas (Felzenszwalb and Huttenlocher 2004), as
// min(envelope, min_a L_r(p - r, a) + w * trunc) for the truncated quadratic.
// Diagonal directions use a weight derived from the 4-neighbour weights around the diagonal
// (SemiGlobalEdgeWeights). Internal to hairmvs_mrf: callers use SolveMrf.

#include <array>
#include <vector>

#include "src/mrf/mrf.h"

namespace hairmvs {

// The scanline directions (dx, dy) in the order they are accumulated.
std::vector<std::array<int, 2>> SemiGlobalDirections(int num_directions);

// Edge weights per direction type, each height * width, indexed by the edge's upper (for
// horizontal edges: left) pixel: right = w(p, p+x), down = w(p, p+y), diag = w(p, p+x+y),
// anti = w(p, p-x+y). The diagonal weight is the mean over the two 2-step paths between the
// pixels of the weaker 4-neighbour weight on each path (a cut across strands stays weak).
struct SemiGlobalEdgeWeights {
  std::vector<float> right, down, diag, anti;
};
SemiGlobalEdgeWeights ComputeSemiGlobalEdgeWeights(const MrfProblem& problem);

// m[b] = min_a prev[a] + weight * min((a * step - (delta + b * step))^2, truncation), for
// b = 0..num_labels-1, with the lower envelope of parabolas (O(L)); prev_min = min_a prev[a].
// The CPU twin of mrf_path_min in kernels/mrf_path_min.clh. v, z: scratch of num_labels and
// num_labels + 1 entries.
void SemiGlobalPathMin(const float* prev, float prev_min, int num_labels, float step, float delta,
                       float weight, float truncation, int* v, float* z, float* m);

// Plain CPU reference (one path at a time, in the same arithmetic order as the kernel).
std::vector<int> SolveSemiGlobalCpu(const MrfProblem& problem, int num_directions);

// OpenCL version (kernels/mrf_sgm.cl): one work-item per scanline path; then, if
// icm_iterations > 0, checkerboard ICM sweeps on the device (kernels/mrf_icm.cl), equal to
// PolishWithIcm(problem, icm_iterations, &labels) on the CPU.
std::vector<int> SolveSemiGlobalOpenCL(const MrfProblem& problem, int num_directions,
                                       int icm_iterations, OpenCLContext* context);

}  // namespace hairmvs
