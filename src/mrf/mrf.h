#pragma once
// The depth-label MRF of the paper's Section 3 (method.md section 2) and its solvers.
//
//   E(D) = sum_p e_d(p, D(p)) + sum_{p,q 4-neighbours} w_pq * min(|D(p) - D(q)|^2, truncation)
//
// with w_pq = lambda * exp(-|O(p) - O(q)|^2 / (2 sigma_o^2)) already folded in by the caller.
// Labels are integers 0..L-1; label l at pixel p means the value
// value(p, l) = label_offset[p] + l * label_step, so a coarse-to-fine caller can give each pixel
// its own band of depths around an upsampled coarse depth map.
//
// Solvers (MrfSolverType), compared by the energy they reach (performance-notes.md):
//  - graph_cuts: alpha-expansion (Boykov, Veksler, Zabih 2001) plus jump moves (all labels
//    +1 / -1) with Boykov-Kolmogorov max-flow. The quadratic term is not a metric, so a move
//    can be non-submodular; such pairwise terms are over-approximated (Rother et al. 2005,
//    "truncation"; see graph_cuts.cc) so that each move never increases the energy.
//    The slowest and the lowest energies (about 1 s of CPU per move per Mpixel here).
//  - semi_global / semi_global_cpu: semi-global matching (Hirschmueller 2008) along 4 or 8
//    scanline directions with the MRF's own pairwise term V_pq; OpenCL / plain CPU reference.
//  - belief_propagation / belief_propagation_cpu: loopy min-sum belief propagation on the
//    4-connected grid, checkerboard updates, O(L) messages; OpenCL / plain CPU reference.
//    On the synthetic stereo-like tests, within 2% of graph cuts' energy.
//  - icm: winner-take-all then iterated conditional modes (a baseline and a polish).
//  - winner_take_all: per-pixel argmin of the data term only.

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "src/mrf/mrf_solver_names.h"

namespace hairmvs {

class OpenCLContext;

struct MrfProblem {
  int width = 0;
  int height = 0;
  int num_labels = 0;
  // [label][row][col], num_labels * height * width.
  std::vector<float> data_cost;
  // Per pixel, height * width; empty = all 0.
  std::vector<float> label_offset;
  // value(p, l) = label_offset[p] + l * label_step.
  float label_step = 1.0f;
  // height * width: w(p, p + x) and w(p, p + y), lambda already folded in. The entries of the
  // last column (weight_right) and the last row (weight_down) are ignored. Empty = all 0.
  std::vector<float> weight_right;
  std::vector<float> weight_down;
  // V_pq(a, b) = w_pq * min((value(p, a) - value(q, b))^2, truncation).
  float truncation = std::numeric_limits<float>::infinity();

  size_t NumPixels() const { return static_cast<size_t>(width) * height; }
  float Cost(int label, size_t pixel) const { return data_cost[label * NumPixels() + pixel]; }
  float Value(size_t pixel, int label) const {
    return (label_offset.empty() ? 0.0f : label_offset[pixel]) + label * label_step;
  }
  // Throws hairmvs::Error naming the inconsistent field.
  void Validate() const;
};

// The pairwise term of an edge with weight w between values a and b.
inline double MrfPairwise(const MrfProblem& problem, float w, float value_a, float value_b) {
  const double d = static_cast<double>(value_a) - value_b;
  return static_cast<double>(w) * std::min(d * d, static_cast<double>(problem.truncation));
}

// E(labels), in double precision. labels: height * width, each in [0, num_labels).
double MrfEnergy(const MrfProblem& problem, const std::vector<int>& labels);
// The data and smoothness parts of E separately (for reports).
void MrfEnergyParts(const MrfProblem& problem, const std::vector<int>& labels,
                    double* data_energy, double* smoothness_energy);

// Per-pixel argmin of the data term (ties: the lowest label).
std::vector<int> WinnerTakeAll(const MrfProblem& problem);

// Iterated conditional modes, checkerboard order: each sweep updates the pixels with
// (row + col) even, then the odd ones; each takes the label minimising its local energy with
// its 4 neighbours fixed (float arithmetic; ties keep the current label). Stops when no label
// changes or after max_iterations sweeps. Never increases E (up to float rounding of the local
// energies). Returns the number of sweeps that changed a label. The CPU reference of
// kernels/mrf_icm.cl.
int PolishWithIcm(const MrfProblem& problem, int max_iterations, std::vector<int>* labels);

enum class MrfSolverType {
  kGraphCuts,
  kSemiGlobal,
  kSemiGlobalCpu,
  kBeliefPropagation,
  kBeliefPropagationCpu,
  kIcm,
  kWinnerTakeAll,
};
std::string ToString(MrfSolverType type);
bool FromString(const std::string& text, MrfSolverType* type);
// True for the solvers that need an OpenCLContext.
bool UsesOpenCL(MrfSolverType type);

struct MrfSolverOptions {
  MrfSolverType solver = MrfSolverType::kGraphCuts;
  // graph_cuts: expansion cycles over all labels (BVZ 2001: most of the decrease comes in the
  // first 2-3 cycles). icm: sweeps.
  int max_cycles = 3;
  // graph_cuts: stop when a cycle lowers E by less than this fraction of |E|. (ICM stops when
  // a sweep changes no label.)
  double min_relative_decrease = 1e-4;
  // semi_global*: 4 (horizontal and vertical) or 8 (plus diagonals) scanline directions.
  int num_directions = 8;
  // belief_propagation*: message-passing iterations (each updates both checkerboard colours).
  int bp_iterations = 30;
  // Any solver: ICM sweeps run on its result (0 = none); never increases E. Cheap (0.07-0.12 s
  // of CPU per sweep per Mpixel at 16-32 labels; stops at the first sweep that changes
  // nothing) and needed by semi_global, whose labels alone are 1.37x graph cuts' energy at
  // 1 Mpixel (1.04x after).
  int icm_polish_iterations = 10;
  // graph_cuts: start from semi-global matching + ICM (OpenCL when a context is given, else
  // the CPU reference) instead of winner-take-all: cheaper max-flows (measured at 1 Mpixel,
  // 16 labels: 12 s instead of 32 s of CPU, the same final energy).
  bool graph_cuts_init_semi_global = true;

  template <typename Visitor>
  void ForEachField(Visitor&& v) {
    v("solver", &solver, kMrfSolverNameList);
    v("max_cycles", &max_cycles, "alpha-expansion cycles (graph_cuts) or ICM sweeps (icm)");
    v("min_relative_decrease", &min_relative_decrease,
      "stop when a cycle lowers the energy by less than this fraction");
    v("num_directions", &num_directions, "semi-global matching scanline directions: 4 or 8");
    v("bp_iterations", &bp_iterations, "belief propagation iterations");
    v("icm_polish_iterations", &icm_polish_iterations,
      "ICM sweeps after the solver (0 = none)");
    v("graph_cuts_init_semi_global", &graph_cuts_init_semi_global,
      "graph_cuts: start from semi-global matching + ICM instead of winner-take-all");
  }
  bool Check(std::string* error) const;
};

struct MrfResult {
  std::vector<int> labels;
  double energy = 0;
  int cycles = 0;
  double seconds = 0;
  std::string BriefReport() const;
};

// Minimises E with the chosen solver. context: needed by the OpenCL solvers (semi_global,
// belief_propagation; hairmvs::Error if null), ignored by the others. Throws hairmvs::Error
// on an invalid problem or options.
MrfResult SolveMrf(const MrfProblem& problem, const MrfSolverOptions& options,
                   OpenCLContext* context);

}  // namespace hairmvs
