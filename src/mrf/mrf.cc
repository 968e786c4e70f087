#include "src/mrf/mrf.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <iomanip>
#include <sstream>

#include "src/core/enum_names.h"
#include "src/core/logging.h"
#include "src/core/timer.h"
#include "src/mrf/belief_propagation.h"
#include "src/mrf/graph_cuts.h"
#include "src/mrf/semi_global.h"

namespace hairmvs {

void MrfProblem::Validate() const {
  THROW_IF(width <= 0 || height <= 0,
           "MrfProblem: width and height must be positive (got " << width << "x" << height << ")");
  THROW_IF(num_labels <= 0, "MrfProblem: num_labels must be positive (got " << num_labels << ")");
  const size_t n = NumPixels();
  THROW_IF(data_cost.size() != n * num_labels,
           "MrfProblem: data_cost has " << data_cost.size() << " entries, expected num_labels * "
                                        << "height * width = " << n * num_labels);
  THROW_IF(!label_offset.empty() && label_offset.size() != n,
           "MrfProblem: label_offset has " << label_offset.size()
                                           << " entries, expected 0 or height * width = " << n);
  THROW_IF(!weight_right.empty() && weight_right.size() != n,
           "MrfProblem: weight_right has " << weight_right.size()
                                           << " entries, expected 0 or height * width = " << n);
  THROW_IF(!weight_down.empty() && weight_down.size() != n,
           "MrfProblem: weight_down has " << weight_down.size()
                                          << " entries, expected 0 or height * width = " << n);
  THROW_IF(!(label_step > 0.0f) || !std::isfinite(label_step),
           "MrfProblem: label_step must be positive and finite (got " << label_step << ")");
  THROW_IF(!(truncation >= 0.0f), "MrfProblem: truncation must be >= 0 (got " << truncation << ")");
  // NaN compares false in every minimum, which the solvers take in different orders (fmin in
  // the kernels, std::min on the host): a NaN cost gave each solver other labels than its CPU
  // twin. +inf is a label ruled out; -inf and NaN are no costs.
  for (size_t i = 0; i < data_cost.size(); ++i) {
    THROW_IF(!(data_cost[i] > -std::numeric_limits<float>::infinity()),
             "MrfProblem: data cost " << data_cost[i] << " at pixel " << i % n << ", label "
                                      << i / n << " (costs must be numbers, +inf at most)");
  }
  for (float offset : label_offset) {
    THROW_IF(!std::isfinite(offset),
             "MrfProblem: label offsets must be finite (got " << offset << ")");
  }
  for (const std::vector<float>* w : {&weight_right, &weight_down}) {
    for (float x : *w) {
      THROW_IF(!(x >= 0.0f) || !std::isfinite(x),
               "MrfProblem: smoothness weights must be finite and >= 0 (got " << x << ")");
    }
  }
}

void MrfEnergyParts(const MrfProblem& problem, const std::vector<int>& labels,
                    double* data_energy, double* smoothness_energy) {
  const int w = problem.width;
  const int h = problem.height;
  CHECK_EQ(labels.size(), problem.NumPixels());
  double data = 0;
  double smooth = 0;
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const size_t p = static_cast<size_t>(row) * w + col;
      const int l = labels[p];
      CHECK(l >= 0 && l < problem.num_labels) << "label " << l << " at pixel " << p;
      data += problem.Cost(l, p);
      const float v = problem.Value(p, l);
      if (col + 1 < w && !problem.weight_right.empty()) {
        smooth += MrfPairwise(problem, problem.weight_right[p], v,
                              problem.Value(p + 1, labels[p + 1]));
      }
      if (row + 1 < h && !problem.weight_down.empty()) {
        smooth += MrfPairwise(problem, problem.weight_down[p], v,
                              problem.Value(p + w, labels[p + w]));
      }
    }
  }
  if (data_energy != nullptr) *data_energy = data;
  if (smoothness_energy != nullptr) *smoothness_energy = smooth;
}

double MrfEnergy(const MrfProblem& problem, const std::vector<int>& labels) {
  double data = 0;
  double smooth = 0;
  MrfEnergyParts(problem, labels, &data, &smooth);
  return data + smooth;
}

std::vector<int> WinnerTakeAll(const MrfProblem& problem) {
  const size_t n = problem.NumPixels();
  std::vector<int> labels(n, 0);
  std::vector<float> best(problem.data_cost.begin(), problem.data_cost.begin() + n);
  for (int l = 1; l < problem.num_labels; ++l) {
    const float* cost = problem.data_cost.data() + l * n;
    for (size_t p = 0; p < n; ++p) {
      if (cost[p] < best[p]) {
        best[p] = cost[p];
        labels[p] = l;
      }
    }
  }
  return labels;
}

int PolishWithIcm(const MrfProblem& problem, int max_iterations, std::vector<int>* labels) {
  // The same float arithmetic, in the same order, as icm_colour in kernels/mrf_icm.cl.
  const int width = problem.width;
  const int height = problem.height;
  const int n = static_cast<int>(problem.NumPixels());
  CHECK_EQ(labels->size(), problem.NumPixels());
  const std::vector<float> zeros(problem.label_offset.empty() || problem.weight_right.empty() ||
                                         problem.weight_down.empty()
                                     ? n
                                     : 0,
                                 0.0f);
  const float* offset = problem.label_offset.empty() ? zeros.data() : problem.label_offset.data();
  const float* weight_right =
      problem.weight_right.empty() ? zeros.data() : problem.weight_right.data();
  const float* weight_down =
      problem.weight_down.empty() ? zeros.data() : problem.weight_down.data();
  const float step = problem.label_step;
  const float truncation = std::min(problem.truncation, std::numeric_limits<float>::max());
  int* lab = labels->data();
  int sweeps = 0;
  for (; sweeps < max_iterations; ++sweeps) {
    bool changed = false;
    for (int colour = 0; colour < 2; ++colour) {
      for (int row = 0; row < height; ++row) {
        for (int col = (row + colour) & 1; col < width; col += 2) {
          const int p = row * width + col;
          float nv[4];
          float nw[4];
          nv[0] = col > 0 ? offset[p - 1] + static_cast<float>(lab[p - 1]) * step : 0.0f;
          nw[0] = col > 0 ? weight_right[p - 1] : 0.0f;
          nv[1] = col + 1 < width ? offset[p + 1] + static_cast<float>(lab[p + 1]) * step : 0.0f;
          nw[1] = col + 1 < width ? weight_right[p] : 0.0f;
          nv[2] = row > 0 ? offset[p - width] + static_cast<float>(lab[p - width]) * step : 0.0f;
          nw[2] = row > 0 ? weight_down[p - width] : 0.0f;
          nv[3] = row + 1 < height ? offset[p + width] + static_cast<float>(lab[p + width]) * step
                                   : 0.0f;
          nw[3] = row + 1 < height ? weight_down[p] : 0.0f;
          const int current = lab[p];
          int best_label = current;
          float best = std::numeric_limits<float>::infinity();
          for (int pass = 0; pass <= problem.num_labels; ++pass) {
            // pass 0 evaluates the current label, so that ties keep it.
            const int l = pass == 0 ? current : pass - 1;
            const float v = offset[p] + static_cast<float>(l) * step;
            float e = problem.data_cost[static_cast<size_t>(l) * n + p];
            for (int k = 0; k < 4; ++k) {
              const float d = v - nv[k];
              e += nw[k] * std::min(d * d, truncation);
            }
            if (e < best) {
              best = e;
              best_label = l;
            }
          }
          if (best_label != current) {
            lab[p] = best_label;
            changed = true;
          }
        }
      }
    }
    if (!changed) break;
  }
  return sweeps;
}

namespace {

constexpr std::pair<MrfSolverType, const char*> kMrfSolverNames[] = {
    {MrfSolverType::kGraphCuts, "graph_cuts"},
    {MrfSolverType::kSemiGlobal, "semi_global"},
    {MrfSolverType::kSemiGlobalCpu, "semi_global_cpu"},
    {MrfSolverType::kBeliefPropagation, "belief_propagation"},
    {MrfSolverType::kBeliefPropagationCpu, "belief_propagation_cpu"},
    {MrfSolverType::kIcm, "icm"},
    {MrfSolverType::kWinnerTakeAll, "winner_take_all"}};

}  // namespace

std::string ToString(MrfSolverType type) { return EnumName(kMrfSolverNames, type); }

bool FromString(const std::string& text, MrfSolverType* type) {
  return EnumFromName(kMrfSolverNames, text, type);
}

bool UsesOpenCL(MrfSolverType type) {
  return type == MrfSolverType::kSemiGlobal || type == MrfSolverType::kBeliefPropagation;
}

bool MrfSolverOptions::Check(std::string* error) const {
  auto fail = [error](const std::string& message) {
    if (error != nullptr) *error = message;
    return false;
  };
  if (max_cycles < 1) return fail("Mrf.max_cycles must be >= 1");
  if (!(min_relative_decrease >= 0)) return fail("Mrf.min_relative_decrease must be >= 0");
  if (num_directions != 4 && num_directions != 8) return fail("Mrf.num_directions must be 4 or 8");
  if (bp_iterations < 1) return fail("Mrf.bp_iterations must be >= 1");
  if (icm_polish_iterations < 0) return fail("Mrf.icm_polish_iterations must be >= 0");
  return true;
}

std::string MrfResult::BriefReport() const {
  std::ostringstream oss;
  oss << "MRF: energy " << std::setprecision(10) << energy << ", " << cycles << " cycles, "
      << std::setprecision(4) << seconds << " s";
  return oss.str();
}

MrfResult SolveMrf(const MrfProblem& problem, const MrfSolverOptions& options,
                   OpenCLContext* context) {
  problem.Validate();
  std::string error;
  THROW_IF(!options.Check(&error), error);
  THROW_IF(UsesOpenCL(options.solver) && context == nullptr,
           "Mrf.solver = " << ToString(options.solver) << " needs an OpenCL context (got null)");
  Timer timer;
  MrfResult result;
  switch (options.solver) {
    case MrfSolverType::kGraphCuts:
      if (options.graph_cuts_init_semi_global) {
        constexpr int kInitIcmSweeps = 10;
        if (context != nullptr) {
          result.labels =
              SolveSemiGlobalOpenCL(problem, options.num_directions, kInitIcmSweeps, context);
        } else {
          result.labels = SolveSemiGlobalCpu(problem, options.num_directions);
          PolishWithIcm(problem, kInitIcmSweeps, &result.labels);
        }
      } else {
        result.labels = WinnerTakeAll(problem);
      }
      result.cycles = SolveAlphaExpansion(problem, options.max_cycles,
                                          options.min_relative_decrease, &result.labels);
      break;
    case MrfSolverType::kSemiGlobal:
      // The ICM polish runs on the device here, on the labels already there.
      result.labels = SolveSemiGlobalOpenCL(problem, options.num_directions,
                                            options.icm_polish_iterations, context);
      result.cycles = 1;
      break;
    case MrfSolverType::kSemiGlobalCpu:
      result.labels = SolveSemiGlobalCpu(problem, options.num_directions);
      result.cycles = 1;
      break;
    case MrfSolverType::kBeliefPropagation:
      result.labels = SolveBeliefPropagationOpenCL(problem, options.bp_iterations,
                                                   options.icm_polish_iterations, context);
      result.cycles = options.bp_iterations;
      break;
    case MrfSolverType::kBeliefPropagationCpu:
      result.labels = SolveBeliefPropagationCpu(problem, options.bp_iterations);
      result.cycles = options.bp_iterations;
      break;
    case MrfSolverType::kIcm:
      result.labels = WinnerTakeAll(problem);
      result.cycles = PolishWithIcm(problem, options.max_cycles, &result.labels);
      break;
    case MrfSolverType::kWinnerTakeAll:
      result.labels = WinnerTakeAll(problem);
      break;
  }
  // (The OpenCL solvers ran their polish on the device.)
  if (options.icm_polish_iterations > 0 && !UsesOpenCL(options.solver)) {
    PolishWithIcm(problem, options.icm_polish_iterations, &result.labels);
  }
  result.energy = MrfEnergy(problem, result.labels);
  result.seconds = timer.ElapsedSeconds();
  return result;
}

}  // namespace hairmvs
