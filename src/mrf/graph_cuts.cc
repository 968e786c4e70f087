#include "src/mrf/graph_cuts.h"

#include <maxflow/graph.h>

#include <algorithm>
#include <cmath>

#include "src/core/logging.h"

namespace hairmvs {
namespace {

using FlowGraph = maxflow::Graph<double, double, double>;

// The binary move energy of one edge (x = 0: keep the current label, x = 1: take alpha) is
// E(x_p, x_q) = e00 + (e10 - e00) x_p + (e11 - e10) x_q + (e01 + e10 - e00 - e11)(1 - x_p) x_q,
// representable by a cut iff e00 + e11 <= e01 + e10 (Kolmogorov and Zabih 2004). The squared
// depth difference is not a metric, so that can fail (e.g. p and q on either side of alpha).
// Then, following Rother, Kumar, Kolmogorov, Blake 2005 ("truncation"), the excess is added to
// e01 and e10: the modified move energy is >= the true one everywhere and equal at x = 0 (the
// current labelling), so the move's minimiser x* satisfies
// E_true(x*) <= E_mod(x*) <= E_mod(0) = E_true(0): a move never increases the energy.
void AddPairwise(FlowGraph* graph, int p, int q, double e00, double e01, double e10, double e11,
                 int* num_non_submodular) {
  const double excess = e00 + e11 - e01 - e10;
  if (excess > 0) {
    e01 += 0.5 * excess;
    e10 += 0.5 * excess;
    ++*num_non_submodular;
  }
  // x = 1 <=> the node ends in the SINK segment; add_tweights(i, cost if x_i = 1, cost if 0).
  graph->add_tweights(p, e10 - e00, 0.0);
  graph->add_tweights(q, e11 - e10, 0.0);
  const double c = e01 + e10 - e00 - e11;  // >= 0 now
  // (1 - x_p) x_q: paid when p is on the source side and q on the sink side: edge p -> q.
  graph->add_edge(p, q, std::max(c, 0.0), 0.0);
}

}  // namespace

int SolveAlphaExpansion(const MrfProblem& problem, int max_cycles, double min_relative_decrease,
                        std::vector<int>* labels) {
  const int w = problem.width;
  const int h = problem.height;
  const int n = static_cast<int>(problem.NumPixels());
  CHECK_EQ(labels->size(), problem.NumPixels());
  const bool has_right = !problem.weight_right.empty();
  const bool has_down = !problem.weight_down.empty();
  const int max_edges = (has_right ? n : 0) + (has_down ? n : 0);
  FlowGraph graph(n, std::max(max_edges, 1));
  std::vector<int> proposal(n);
  std::vector<int> fused(n);
  double energy = MrfEnergy(problem, *labels);

  // One fusion move (Lempitsky et al. 2010): each pixel keeps its label (x = 0) or takes
  // proposal[p] (x = 1), whichever combination minimises the (over-approximated) energy.
  auto fuse = [&]() {
    graph.reset();
    graph.add_node(n);
    int num_non_submodular = 0;
    for (int p = 0; p < n; ++p) {
      graph.add_tweights(p, problem.Cost(proposal[p], p), problem.Cost((*labels)[p], p));
    }
    auto edge = [&](int p, int q, float weight) {
      if (weight == 0.0f) return;
      const float vp0 = problem.Value(p, (*labels)[p]);
      const float vq0 = problem.Value(q, (*labels)[q]);
      const float vp1 = problem.Value(p, proposal[p]);
      const float vq1 = problem.Value(q, proposal[q]);
      AddPairwise(&graph, p, q, MrfPairwise(problem, weight, vp0, vq0),
                  MrfPairwise(problem, weight, vp0, vq1), MrfPairwise(problem, weight, vp1, vq0),
                  MrfPairwise(problem, weight, vp1, vq1), &num_non_submodular);
    };
    for (int row = 0; row < h; ++row) {
      for (int col = 0; col < w; ++col) {
        const int p = row * w + col;
        if (has_right && col + 1 < w) edge(p, p + 1, problem.weight_right[p]);
        if (has_down && row + 1 < h) edge(p, p + w, problem.weight_down[p]);
      }
    }
    graph.maxflow();
    bool any_change = false;
    for (int p = 0; p < n; ++p) {
      fused[p] = graph.what_segment(p) == FlowGraph::SINK ? proposal[p] : (*labels)[p];
      any_change |= fused[p] != (*labels)[p];
    }
    if (!any_change) return;
    // The construction guarantees no increase up to rounding; accept only strict decreases
    // so that rounding can never make the energy creep up.
    const double fused_energy = MrfEnergy(problem, fused);
    if (fused_energy < energy) {
      labels->swap(fused);
      energy = fused_energy;
    }
    VLOG(2) << "move: E = " << energy << ", " << num_non_submodular
            << " non-submodular edges over-approximated";
  };

  int cycles = 0;
  while (cycles < max_cycles) {
    ++cycles;
    const double cycle_start_energy = energy;
    // Expansion moves: every pixel may take label alpha (BVZ 2001).
    for (int alpha = 0; alpha < problem.num_labels; ++alpha) {
      std::fill(proposal.begin(), proposal.end(), alpha);
      fuse();
    }
    // Jump moves (Veksler 1999): every pixel may move one label up, or down. The quadratic
    // prior prefers smooth slopes, which an expansion (one label for all movers) can only
    // reach pixel band by pixel band; with per-pixel offsets a constant depth is not even a
    // constant label. Pixels at the ends of the label range keep their label.
    for (int jump : {1, -1}) {
      for (int p = 0; p < n; ++p) {
        proposal[p] = std::clamp((*labels)[p] + jump, 0, problem.num_labels - 1);
      }
      fuse();
    }
    if (cycle_start_energy - energy <= min_relative_decrease * std::abs(cycle_start_energy)) break;
  }
  return cycles;
}

}  // namespace hairmvs
