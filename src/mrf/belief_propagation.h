#pragma once
// Loopy min-sum belief propagation on the 4-connected MRF of src/mrf/mrf.h, checkerboard
// schedule (Felzenszwalb and Huttenlocher 2006): each iteration updates the messages sent by
// the pixels with (row + col) even, then by the odd ones. Messages are computed in O(L) with
// the lower envelope of parabolas (SemiGlobalPathMin), normalised to min 0. The labels are the
// argmin of the beliefs after the last iteration. Internal to hairmvs_mrf: use SolveMrf.

#include <vector>

#include "src/mrf/mrf.h"

namespace hairmvs {

// Plain CPU reference (same float arithmetic order as kernels/mrf_bp.cl).
std::vector<int> SolveBeliefPropagationCpu(const MrfProblem& problem, int iterations);

// OpenCL version (kernels/mrf_bp.cl): one work-item per pixel and colour pass; then, if
// icm_iterations > 0, checkerboard ICM sweeps on the device (kernels/mrf_icm.cl).
std::vector<int> SolveBeliefPropagationOpenCL(const MrfProblem& problem, int iterations,
                                              int icm_iterations, OpenCLContext* context);

}  // namespace hairmvs
