// MRF solvers at about 1 Mpixel on the synthetic stereo-like problem (src/mrf/mrf_synthetic.h):
// seconds per solve, and the energy reached relative to graph cuts on the same volume
// (counter E_rel_gc, when BM_GraphCuts of that size ran first in the same process; compare
// solvers by energy, performance-notes.md).
//
//   ./build/bench/mrf_benchmark --benchmark_filter=1024
//
// Arguments: width, height, labels[, directions, ICM sweeps]. lambda = 0.5. "Time" is wall
// time, "CPU" the CPU time of the whole process (all threads, PoCL's included): on a shared
// machine the CPU time is the steadier measure of work.

#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <tuple>

#include "src/mrf/mrf.h"
#include "src/mrf/mrf_synthetic.h"
#include "src/opencl/opencl_context.h"

namespace hairmvs {
namespace {

constexpr float kLambda = 0.5f;

const MrfProblem& Problem(int width, int height, int num_labels) {
  static std::map<std::tuple<int, int, int>, std::unique_ptr<MrfProblem>> cache;
  auto& entry = cache[{width, height, num_labels}];
  if (!entry) {
    entry = std::make_unique<MrfProblem>(
        SyntheticStereoMrfProblem(width, height, num_labels, kLambda, 1));
  }
  return *entry;
}

// Graph cuts from winner-take-all: the reference energy.
MrfSolverOptions GraphCutOptions() {
  MrfSolverOptions options;
  options.solver = MrfSolverType::kGraphCuts;
  options.max_cycles = 3;
  options.graph_cuts_init_semi_global = false;
  options.icm_polish_iterations = 0;
  return options;
}

// Graph-cut energies by problem size, recorded by BM_GraphCuts (registered first, so it runs
// before the other solvers of the same size when the filter selects it).
std::map<std::tuple<int, int, int>, double>& GraphCutEnergies() {
  static std::map<std::tuple<int, int, int>, double> energies;
  return energies;
}

OpenCLContext* Context() {
  static std::shared_ptr<OpenCLContext> context = OpenCLContext::Create();
  return context.get();
}

void RunSolver(benchmark::State& state, const MrfSolverOptions& options) {
  const int width = state.range(0);
  const int height = state.range(1);
  const int num_labels = state.range(2);
  const MrfProblem& problem = Problem(width, height, num_labels);
  OpenCLContext* context =
      UsesOpenCL(options.solver) || options.graph_cuts_init_semi_global ? Context() : nullptr;
  if (context != nullptr) SolveMrf(problem, options, context);  // builds the programs
  MrfResult result;
  for (auto _ : state) {
    result = SolveMrf(problem, options, context);
  }
  state.counters["E"] = result.energy;
  const std::tuple<int, int, int> key = {width, height, num_labels};
  if (options.solver == MrfSolverType::kGraphCuts && !options.graph_cuts_init_semi_global) {
    GraphCutEnergies()[key] = result.energy;
  }
  const auto gc = GraphCutEnergies().find(key);
  if (gc != GraphCutEnergies().end()) state.counters["E_rel_gc"] = result.energy / gc->second;
  state.counters["cycles"] = result.cycles;
  state.counters["Mpixel_per_s"] = benchmark::Counter(
      static_cast<double>(problem.NumPixels()) * 1e-6,
      benchmark::Counter::kIsIterationInvariantRate);
}

void BM_GraphCuts(benchmark::State& state) { RunSolver(state, GraphCutOptions()); }

// Graph cuts started from semi-global matching + ICM (OpenCL, 8 directions).
void BM_GraphCutsFromSemiGlobal(benchmark::State& state) {
  MrfSolverOptions options = GraphCutOptions();
  options.graph_cuts_init_semi_global = true;
  RunSolver(state, options);
}

void BM_SemiGlobalOpenCL(benchmark::State& state) {
  MrfSolverOptions options;
  options.solver = MrfSolverType::kSemiGlobal;
  options.num_directions = state.range(3);
  options.icm_polish_iterations = state.range(4);
  RunSolver(state, options);
}

void BM_SemiGlobalCpu(benchmark::State& state) {
  MrfSolverOptions options;
  options.solver = MrfSolverType::kSemiGlobalCpu;
  options.num_directions = state.range(3);
  options.icm_polish_iterations = state.range(4);
  RunSolver(state, options);
}

void BM_BeliefPropagationOpenCL(benchmark::State& state) {
  MrfSolverOptions options;
  options.solver = MrfSolverType::kBeliefPropagation;
  options.bp_iterations = state.range(3);
  options.icm_polish_iterations = state.range(4);
  RunSolver(state, options);
}

void BM_Icm(benchmark::State& state) {
  MrfSolverOptions options;
  options.solver = MrfSolverType::kIcm;
  options.max_cycles = 20;
  options.icm_polish_iterations = 0;
  RunSolver(state, options);
}

void BM_WinnerTakeAll(benchmark::State& state) {
  MrfSolverOptions options;
  options.solver = MrfSolverType::kWinnerTakeAll;
  RunSolver(state, options);
}

// A quick size, then about 1 Mpixel with 16 and 32 labels.
void Sizes(benchmark::internal::Benchmark* b) {
  b->Args({256, 256, 16})->Args({1024, 1024, 16})->Args({1024, 1024, 32});
  b->Iterations(1)->Unit(benchmark::kSecond)->MeasureProcessCPUTime()->UseRealTime();
}
// Sizes x directions (4, 8) x ICM polish sweeps (0, 10).
void SemiGlobalArgs(benchmark::internal::Benchmark* b) {
  for (int num_labels : {16, 32}) {
    for (int size : {256, 1024}) {
      if (size == 256 && num_labels == 32) continue;
      for (int directions : {4, 8}) {
        for (int icm : {0, 10}) b->Args({size, size, num_labels, directions, icm});
      }
    }
  }
  b->Iterations(1)->Unit(benchmark::kSecond)->MeasureProcessCPUTime()->UseRealTime();
}

BENCHMARK(BM_GraphCuts)->Apply(Sizes);
BENCHMARK(BM_GraphCutsFromSemiGlobal)->Apply(Sizes);
BENCHMARK(BM_SemiGlobalOpenCL)->Apply(SemiGlobalArgs);
BENCHMARK(BM_SemiGlobalCpu)
    ->Args({256, 256, 16, 8, 10})->Args({1024, 1024, 16, 8, 10})->Args({1024, 1024, 32, 8, 10})
    ->Iterations(1)->Unit(benchmark::kSecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_BeliefPropagationOpenCL)
    ->Args({256, 256, 16, 30, 0})->Args({256, 256, 16, 30, 10})
    ->Args({1024, 1024, 16, 10, 10})->Args({1024, 1024, 16, 30, 10})
    ->Args({1024, 1024, 32, 30, 10})
    ->Iterations(1)->Unit(benchmark::kSecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK(BM_Icm)->Apply(Sizes);
BENCHMARK(BM_WinnerTakeAll)->Apply(Sizes);

}  // namespace
}  // namespace hairmvs

BENCHMARK_MAIN();
