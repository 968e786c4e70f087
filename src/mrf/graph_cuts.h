#pragma once
// Alpha-expansion (Boykov, Veksler, Zabih 2001) with Boykov-Kolmogorov max-flow, for the MRF of
// src/mrf/mrf.h. Internal to hairmvs_mrf: callers use SolveMrf.

#include <vector>

#include "src/mrf/mrf.h"

namespace hairmvs {

// Runs cycles of moves (one expansion move per label, in label order, then a jump move of all
// pixels one label up and one down) starting from *labels,
// until a cycle lowers E by less than min_relative_decrease * |E| or max_cycles cycles.
// Each move is solved exactly for a submodular over-approximation of the move energy that is
// tight at the current labelling, so E never increases (see graph_cuts.cc).
// Returns the number of cycles run.
int SolveAlphaExpansion(const MrfProblem& problem, int max_cycles, double min_relative_decrease,
                        std::vector<int>* labels);

}  // namespace hairmvs
