#include "src/mrf/mrf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <utility>

#include "src/core/logging.h"
#include "src/core/option_parser.h"
#include "src/core/test_util.h"
#include "src/mrf/graph_cuts.h"
#include "src/mrf/icm_opencl.h"
#include "src/mrf/mrf_synthetic.h"
#include "src/mrf/semi_global.h"
#include "src/opencl/opencl_context.h"

namespace hairmvs {
namespace {

// Uniform random data costs in [0, 1) and weights in [0, max_weight).
MrfProblem RandomProblem(int width, int height, int num_labels, float max_weight, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  MrfProblem problem;
  problem.width = width;
  problem.height = height;
  problem.num_labels = num_labels;
  const size_t n = problem.NumPixels();
  problem.data_cost.resize(n * num_labels);
  for (float& c : problem.data_cost) c = unit(rng);
  problem.weight_right.resize(n);
  problem.weight_down.resize(n);
  for (size_t p = 0; p < n; ++p) {
    problem.weight_right[p] = max_weight * unit(rng);
    problem.weight_down[p] = max_weight * unit(rng);
  }
  return problem;
}

// The exact minimum by enumeration (tiny problems only).
double BruteForceMinimum(const MrfProblem& problem) {
  const size_t n = problem.NumPixels();
  std::vector<int> labels(n, 0);
  double best = std::numeric_limits<double>::infinity();
  while (true) {
    best = std::min(best, MrfEnergy(problem, labels));
    size_t i = 0;
    while (i < n && ++labels[i] == problem.num_labels) labels[i++] = 0;
    if (i == n) break;
  }
  return best;
}

// The exact minimum of a chain (one row or one column) by dynamic programming over its labels,
// independent of every solver.
double ChainMinimum(const MrfProblem& problem) {
  CHECK(problem.width == 1 || problem.height == 1);
  const std::vector<float>& weights = problem.height == 1 ? problem.weight_right
                                                          : problem.weight_down;
  std::vector<double> best(problem.num_labels);  // of the chain up to p, p's label given
  for (int l = 0; l < problem.num_labels; ++l) best[l] = problem.Cost(l, 0);
  for (size_t p = 1; p < problem.NumPixels(); ++p) {
    const float w = weights.empty() ? 0.0f : weights[p - 1];
    std::vector<double> next(problem.num_labels);
    for (int l = 0; l < problem.num_labels; ++l) {
      double lowest = std::numeric_limits<double>::infinity();
      for (int k = 0; k < problem.num_labels; ++k) {
        lowest = std::min(lowest, best[k] + MrfPairwise(problem, w, problem.Value(p - 1, k),
                                                        problem.Value(p, l)));
      }
      next[l] = problem.Cost(l, p) + lowest;
    }
    best = next;
  }
  return *std::min_element(best.begin(), best.end());
}

// Whether no single pixel's label can be changed to lower the energy (ICM's fixed point).
bool IsSingleSiteMinimum(const MrfProblem& problem, std::vector<int> labels, std::string* where) {
  const double energy = MrfEnergy(problem, labels);
  for (size_t p = 0; p < problem.NumPixels(); ++p) {
    const int own = labels[p];
    for (int l = 0; l < problem.num_labels; ++l) {
      labels[p] = l;
      const double moved = MrfEnergy(problem, labels);
      if (moved < energy - 1e-6 * std::max(1.0, std::abs(energy))) {
        *where = "pixel " + std::to_string(p) + ": label " + std::to_string(own) + " -> " +
                 std::to_string(l) + " lowers " + std::to_string(energy) + " to " +
                 std::to_string(moved);
        return false;
      }
    }
    labels[p] = own;
  }
  return true;
}

MrfResult Solve(const MrfProblem& problem, MrfSolverType type, OpenCLContext* context = nullptr,
                int num_directions = 8, int icm_polish_iterations = 0) {
  MrfSolverOptions options;
  options.icm_polish_iterations = icm_polish_iterations;
  options.solver = type;
  options.max_cycles = 10;
  options.num_directions = num_directions;
  return SolveMrf(problem, options, context);
}

std::shared_ptr<OpenCLContext> Context() {
  static std::shared_ptr<OpenCLContext> context = OpenCLContext::Create();
  return context;
}

TEST(MrfEnergy, MatchesAHandComputedValue) {
  // 2x2 pixels, 2 labels, offsets and truncation.
  MrfProblem problem;
  problem.width = 2;
  problem.height = 2;
  problem.num_labels = 2;
  problem.data_cost = {1, 2, 3, 4, /* label 1: */ 5, 6, 7, 8};
  problem.label_offset = {0, 1, 0, 0.5f};
  problem.label_step = 2;
  problem.weight_right = {1, 100, 2, 100};  // last column ignored
  problem.weight_down = {3, 4, 100, 100};   // last row ignored
  problem.truncation = 4;
  const std::vector<int> labels = {0, 1, 1, 0};  // values 0, 3, 2, 0.5
  // data 1 + 6 + 7 + 4 = 18; right: 1*min(9,4) + 2*min(2.25,4) = 8.5;
  // down: 3*min(4,4) + 4*min(6.25,4) = 28.
  double data = 0;
  double smooth = 0;
  MrfEnergyParts(problem, labels, &data, &smooth);
  EXPECT_DOUBLE_EQ(data, 18.0);
  EXPECT_DOUBLE_EQ(smooth, 36.5);
  EXPECT_DOUBLE_EQ(MrfEnergy(problem, labels), 54.5);
}

TEST(MrfProblem, ValidateNamesTheBadField) {
  MrfProblem problem = RandomProblem(4, 3, 2, 1.0f, 1);
  problem.label_offset.resize(5);
  try {
    problem.Validate();
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("label_offset"), std::string::npos) << e.what();
  }
  problem = RandomProblem(4, 3, 2, 1.0f, 1);
  problem.data_cost.pop_back();
  EXPECT_THROW(SolveMrf(problem, MrfSolverOptions(), nullptr), Error);
  // A NaN or -inf cost, a non-finite offset: refused, naming the pixel and label; +inf (a
  // label ruled out) is a cost.
  for (const float bad : {std::nanf(""), -std::numeric_limits<float>::infinity()}) {
    problem = RandomProblem(4, 3, 2, 1.0f, 1);
    problem.data_cost[12 + 5] = bad;  // label 1, pixel 5
    const std::string message = testing_util::ErrorOf([&] { problem.Validate(); });
    EXPECT_NE(message.find("at pixel 5, label 1"), std::string::npos) << message;
  }
  problem = RandomProblem(4, 3, 2, 1.0f, 1);
  problem.data_cost[3] = std::numeric_limits<float>::infinity();
  EXPECT_NO_THROW(problem.Validate());
  problem.label_offset.assign(12, 0.0f);
  problem.label_offset[2] = std::nanf("");
  EXPECT_NE(testing_util::ErrorOf([&] { problem.Validate(); }).find("label offsets must be finite"),
            std::string::npos);
}

TEST(MrfSolverOptions, NamesRoundTripAndCheck) {
  // The help texts' list (kMrfSolverNameList), split at " | ": exactly the solvers' names.
  std::set<std::string> listed;
  const std::string list = kMrfSolverNameList;
  for (size_t begin = 0; begin <= list.size();) {
    const size_t end = std::min(list.find(" | ", begin), list.size());
    listed.insert(list.substr(begin, end - begin));
    begin = end + 3;
  }
  std::set<std::string> names;
  for (MrfSolverType t : {MrfSolverType::kGraphCuts, MrfSolverType::kSemiGlobal,
                          MrfSolverType::kSemiGlobalCpu, MrfSolverType::kBeliefPropagation,
                          MrfSolverType::kBeliefPropagationCpu, MrfSolverType::kIcm,
                          MrfSolverType::kWinnerTakeAll}) {
    MrfSolverType parsed = MrfSolverType::kWinnerTakeAll;
    ASSERT_TRUE(FromString(ToString(t), &parsed)) << ToString(t);
    EXPECT_EQ(parsed, t);
    names.insert(ToString(t));
  }
  EXPECT_EQ(listed, names) << kMrfSolverNameList;
  MrfSolverType parsed;
  EXPECT_FALSE(FromString("graphcuts", &parsed));
  MrfSolverOptions options;
  std::string error;
  EXPECT_TRUE(options.Check(&error));
  options.num_directions = 6;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("num_directions"), std::string::npos);
  options.num_directions = 4;
  options.solver = MrfSolverType::kSemiGlobal;
  EXPECT_THROW(SolveMrf(RandomProblem(3, 3, 2, 1, 1), options, nullptr), Error);
}

TEST(MrfSolverOptions, ParseFromTheCommandLine) {
  MrfSolverOptions options;
  OptionParser parser("mrf", "test");
  parser.AddSection("Mrf", &options);
  std::vector<std::string> args = {"hairmvs", "mrf", "--Mrf.solver", "belief_propagation",
                                   "--Mrf.bp_iterations", "7", "--Mrf.num_directions", "4"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  ASSERT_TRUE(parser.Parse(static_cast<int>(argv.size()), argv.data()));
  EXPECT_EQ(options.solver, MrfSolverType::kBeliefPropagation);
  EXPECT_EQ(options.bp_iterations, 7);
  EXPECT_EQ(options.num_directions, 4);
  OptionParser bad_parser("mrf", "test");
  bad_parser.AddSection("Mrf", &options);
  args[3] = "no_such_solver";
  argv.clear();
  for (auto& a : args) argv.push_back(a.data());
  EXPECT_THROW(bad_parser.Parse(static_cast<int>(argv.size()), argv.data()), Error);
}

// Graph cuts against the exact optimum on 3x3 pixels, 3 labels, for weak and strong
// smoothness (strong weights make many expansion moves non-submodular for the quadratic term),
// with and without truncation and label offsets.
TEST(GraphCuts, NearTheExactOptimumOnTinyProblems) {
  int count = 0;
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    for (float max_weight : {0.05f, 0.3f, 2.0f}) {
      for (bool variant : {false, true}) {
        MrfProblem problem = RandomProblem(3, 3, 3, max_weight, seed);
        if (variant) {
          problem.truncation = 1.5f;
          problem.label_step = 0.7f;
          problem.label_offset.resize(9);
          for (int p = 0; p < 9; ++p) problem.label_offset[p] = 0.3f * (p % 4);
        }
        const double optimum = BruteForceMinimum(problem);
        const double initial = MrfEnergy(problem, WinnerTakeAll(problem));
        std::vector<int> icm_labels = WinnerTakeAll(problem);
        PolishWithIcm(problem, 100, &icm_labels);
        // From winner-take-all (the classic start) and from semi-global matching (default).
        for (bool init_semi_global : {false, true}) {
          MrfSolverOptions options;
          options.max_cycles = 10;
          options.graph_cuts_init_semi_global = init_semi_global;
          const MrfResult gc = SolveMrf(problem, options, nullptr);
          EXPECT_NEAR(gc.energy, MrfEnergy(problem, gc.labels), 1e-9);
          EXPECT_LE(gc.energy, initial + 1e-9);
          EXPECT_GE(gc.energy, optimum - 1e-9);
          EXPECT_LE(gc.energy, optimum * 1.05 + 1e-9)
              << "seed " << seed << " max_weight " << max_weight << " variant " << variant
              << " init_semi_global " << init_semi_global;
          EXPECT_LE(gc.energy, MrfEnergy(problem, icm_labels) + 1e-9);
          count += gc.energy <= optimum + 1e-9;
        }
      }
    }
  }
  // Most of these tiny problems are solved exactly (all 72 runs when measured; without the
  // jump moves, 31 of 36 from winner-take-all, the worst 14% above the optimum, with strong
  // truncated couplings and offsets).
  EXPECT_GE(count, 60);
  LOG(INFO) << "graph cuts found the exact optimum in " << count << " of 72 runs";
}

// A non-submodular expansion: p and q on either side of alpha with a strong edge. The move
// must never increase the energy.
TEST(GraphCuts, NonSubmodularMovesNeverIncreaseTheEnergy) {
  for (uint32_t seed = 1; seed <= 20; ++seed) {
    MrfProblem problem = RandomProblem(6, 5, 7, 20.0f, seed);
    std::vector<int> labels(problem.NumPixels());
    std::mt19937 rng(seed);
    for (int& l : labels) l = std::uniform_int_distribution<int>(0, 6)(rng);
    double energy = MrfEnergy(problem, labels);
    for (int cycle = 0; cycle < 3; ++cycle) {
      SolveAlphaExpansion(problem, 1, 0.0, &labels);
      const double next = MrfEnergy(problem, labels);
      EXPECT_LE(next, energy + 1e-9);
      energy = next;
    }
  }
}

// 24x20 stereo-like problems with 8 and 16 labels: graph cuts beat winner-take-all, ICM
// cannot polish them much further, and semi-global matching followed by ICM comes within 25%
// of graph cuts (within 2% for the weaker smoothness); belief propagation within 5% (measured:
// 0-1.8%). Raw semi-global matching is a heuristic whose labels do not minimise E: it is only
// asserted to beat winner-take-all by far.
TEST(GraphCuts, StereoLikeProblemsAgainstOtherSolvers) {
  for (int num_labels : {8, 16}) {
    for (float lambda : {0.2f, 1.0f}) {
      const MrfProblem problem =
          SyntheticStereoMrfProblem(24, 20, num_labels, lambda, 7 + num_labels);
      const double wta = MrfEnergy(problem, WinnerTakeAll(problem));
      const MrfResult gc = Solve(problem, MrfSolverType::kGraphCuts);
      EXPECT_LT(gc.energy, wta);
      std::vector<int> polished = gc.labels;
      PolishWithIcm(problem, 100, &polished);
      const double polished_energy = MrfEnergy(problem, polished);
      EXPECT_LE(polished_energy, gc.energy + 1e-9);
      EXPECT_GE(polished_energy, gc.energy * 0.99);
      const MrfResult icm = Solve(problem, MrfSolverType::kIcm);
      const MrfResult sgm4 = Solve(problem, MrfSolverType::kSemiGlobalCpu, nullptr, 4);
      const MrfResult sgm8 = Solve(problem, MrfSolverType::kSemiGlobalCpu, nullptr, 8);
      const MrfResult sgm8_icm = Solve(problem, MrfSolverType::kSemiGlobalCpu, nullptr, 8, 100);
      const MrfResult bp = Solve(problem, MrfSolverType::kBeliefPropagationCpu);
      const MrfResult bp_icm =
          Solve(problem, MrfSolverType::kBeliefPropagationCpu, nullptr, 8, 100);
      EXPECT_GE(icm.energy, gc.energy * 0.999);
      EXPECT_LE(sgm8_icm.energy, gc.energy * (lambda < 0.5f ? 1.03 : 1.25));
      EXPECT_LE(sgm8.energy, gc.energy * 2.0);
      EXPECT_LE(sgm4.energy, gc.energy * 2.0);
      EXPECT_LT(sgm8.energy * 2, wta);
      EXPECT_LE(bp.energy, gc.energy * 1.05);
      EXPECT_LE(bp_icm.energy, bp.energy + 1e-9);
      LOG(INFO) << "L=" << num_labels << " lambda=" << lambda << ": E/E_gc wta "
                << wta / gc.energy << ", icm " << icm.energy / gc.energy << ", sgm4 "
                << sgm4.energy / gc.energy << ", sgm8 " << sgm8.energy / gc.energy
                << ", sgm8+icm " << sgm8_icm.energy / gc.energy << ", bp " << bp.energy / gc.energy
                << ", bp+icm " << bp_icm.energy / gc.energy
                << " (gc cycles " << gc.cycles << ")";
    }
  }
}

// Per-pixel offsets that shift values by whole steps give the same energies as the equivalent
// problem without offsets whose labels outside each pixel's band cost a prohibitive amount.
TEST(MrfProblem, LabelOffsetsMatchTheEquivalentProblemWithoutOffsets) {
  const int band = 3;
  const int shift_max = 2;
  MrfProblem banded = RandomProblem(3, 3, band, 0.5f, 11);
  banded.label_step = 0.5f;
  banded.truncation = 2.0f;
  banded.label_offset.resize(9);
  std::vector<int> shift(9);
  for (int p = 0; p < 9; ++p) {
    shift[p] = (p * 7) % (shift_max + 1);
    banded.label_offset[p] = 10.0f + shift[p] * banded.label_step;
  }
  MrfProblem full = banded;
  full.num_labels = band + shift_max;
  full.label_offset.assign(9, 10.0f);
  full.data_cost.assign(9 * full.num_labels, 1e4f);
  for (int p = 0; p < 9; ++p) {
    for (int l = 0; l < band; ++l) full.data_cost[(shift[p] + l) * 9 + p] = banded.Cost(l, p);
  }
  std::mt19937 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<int> labels(9);
    std::vector<int> full_labels(9);
    for (int p = 0; p < 9; ++p) {
      labels[p] = std::uniform_int_distribution<int>(0, band - 1)(rng);
      full_labels[p] = labels[p] + shift[p];
    }
    EXPECT_NEAR(MrfEnergy(banded, labels), MrfEnergy(full, full_labels), 1e-9);
  }
  const double optimum = BruteForceMinimum(banded);
  EXPECT_NEAR(optimum, BruteForceMinimum(full), 1e-9);
  const MrfResult gc = Solve(banded, MrfSolverType::kGraphCuts);
  EXPECT_LE(gc.energy, optimum * 1.05 + 1e-9);
  const MrfResult gc_full = Solve(full, MrfSolverType::kGraphCuts);
  EXPECT_LE(gc_full.energy, optimum * 1.05 + 1e-9);
}

// The O(L) lower-envelope minimum of a path step equals the O(L^2) brute force.
TEST(SemiGlobal, PathMinimumEqualsBruteForce) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int trial = 0; trial < 2000; ++trial) {
    const int num_labels = 1 + trial % 33;
    std::vector<float> prev(num_labels);
    for (float& x : prev) x = (trial % 3 == 0 ? 100.0f : 3.0f) * unit(rng);
    const float prev_min = *std::min_element(prev.begin(), prev.end());
    const float step = 0.1f + 2.0f * unit(rng);
    const float delta = (unit(rng) - 0.5f) * 3.0f * step * num_labels;
    const float weight = trial % 7 == 0 ? 0.0f : std::pow(10.0f, 4.0f * unit(rng) - 2.0f);
    const float truncation = trial % 2 ? 1e30f : 5.0f * unit(rng) * step * step;
    std::vector<int> v(num_labels);
    std::vector<float> z(num_labels + 1);
    std::vector<float> m(num_labels);
    SemiGlobalPathMin(prev.data(), prev_min, num_labels, step, delta, weight, truncation,
                      v.data(), z.data(), m.data());
    for (int b = 0; b < num_labels; ++b) {
      double best = std::numeric_limits<double>::infinity();
      for (int a = 0; a < num_labels; ++a) {
        const double d = static_cast<double>(a) * step - (delta + static_cast<double>(b) * step);
        best = std::min(best, prev[a] + static_cast<double>(weight) *
                                            std::min(d * d, static_cast<double>(truncation)));
      }
      ASSERT_NEAR(m[b], best, 1e-4 * (1.0 + std::abs(best)))
          << "trial " << trial << " L " << num_labels << " b " << b;
    }
  }
}

// Independent of the kernels' CPU copies: on a chain, the four scanline paths of semi-global
// matching are the chain's dynamic programme in both directions (O(L^2) here) and two paths of
// one pixel (its data cost), so the device's labels are the argmin of their sum; rows and
// columns, with label offsets and a truncation that binds.
TEST(SemiGlobal, ChainIsBothDynamicProgrammesPlusTwiceTheDataCost) {
  for (const auto& [width, height] : {std::pair<int, int>{15, 1}, std::pair<int, int>{1, 15}}) {
    MrfProblem problem = RandomProblem(width, height, 7, 0.8f, 31 + width);
    problem.truncation = 2.0f;
    problem.label_step = 0.5f;
    problem.label_offset.resize(problem.NumPixels());
    for (size_t p = 0; p < problem.NumPixels(); ++p) problem.label_offset[p] = 0.3f * (p % 4);
    const int n = static_cast<int>(problem.NumPixels()), num_labels = problem.num_labels;
    // The weight of the edge between chain pixels p and p + 1.
    auto weight = [&](int p) {
      return static_cast<double>(width > 1 ? problem.weight_right[p] : problem.weight_down[p]);
    };
    auto pairwise = [&](int p, int a, int q, int b) {
      const double d = problem.Value(p, a) - problem.Value(q, b);
      return weight(std::min(p, q)) * std::min(d * d, static_cast<double>(problem.truncation));
    };
    std::vector<std::vector<double>> sum(n, std::vector<double>(num_labels, 0.0));
    for (int direction : {1, -1}) {
      std::vector<double> previous;
      for (int i = 0; i < n; ++i) {
        const int p = direction > 0 ? i : n - 1 - i;
        std::vector<double> path(num_labels);
        for (int b = 0; b < num_labels; ++b) {
          path[b] = problem.Cost(b, p);
          if (!previous.empty()) {
            const int q = p - direction;
            double best = std::numeric_limits<double>::infinity();
            for (int a = 0; a < num_labels; ++a) {
              best = std::min(best, previous[a] + pairwise(q, a, p, b));
            }
            path[b] += best - *std::min_element(previous.begin(), previous.end());
          }
          sum[p][b] += path[b];
        }
        previous = path;
      }
    }
    std::vector<int> expected(n);
    for (int p = 0; p < n; ++p) {
      for (int b = 0; b < num_labels; ++b) sum[p][b] += 2.0 * problem.Cost(b, p);
      expected[p] = static_cast<int>(std::min_element(sum[p].begin(), sum[p].end()) -
                                     sum[p].begin());
    }
    EXPECT_EQ(SolveSemiGlobalOpenCL(problem, 4, 0, Context().get()), expected)
        << width << " x " << height;
  }
}

// Independent of the kernels' CPU copies, in 2-D with all 8 directions: each direction's
// dynamic programme in double precision with a brute-force inner minimum, the diagonal edges
// weighted as semi_global.h defines (the mean over the two 2-step paths of each path's weaker
// 4-neighbour weight). The chain test above reaches neither the diagonals nor their weights
// (found by the MRF review: swapping the diagonal and anti-diagonal weights passed every test).
// Compared up to ties: each pixel's label must be within 1e-4 of its minimum aggregated cost.
TEST(SemiGlobal, EightDirectionsInTwoDimensionsEqualAPlainDynamicProgramme) {
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    const int width = 5 + static_cast<int>(seed) % 7, height = 4 + static_cast<int>(seed) % 5;
    MrfProblem problem = RandomProblem(width, height, 2 + static_cast<int>(seed) % 6, 1.5f, seed);
    if (seed % 2 == 1) {
      problem.truncation = 2.0f;
      problem.label_step = 0.6f;
      problem.label_offset.resize(problem.NumPixels());
      for (size_t p = 0; p < problem.NumPixels(); ++p) problem.label_offset[p] = 0.1f * (p % 7);
    }
    const int num_labels = problem.num_labels;
    const size_t n = problem.NumPixels();
    auto right = [&](int col, int row) {  // the edge (col, row) - (col + 1, row)
      return static_cast<double>(problem.weight_right[static_cast<size_t>(row) * width + col]);
    };
    auto down = [&](int col, int row) {  // the edge (col, row) - (col, row + 1)
      return static_cast<double>(problem.weight_down[static_cast<size_t>(row) * width + col]);
    };
    // The weight of the edge from (col, row) to (col + dx, row + dy).
    auto weight = [&](int col, int row, int dx, int dy) {
      const int col2 = col + dx, row2 = row + dy;
      if (dy == 0) return right(std::min(col, col2), row);
      if (dx == 0) return down(col, std::min(row, row2));
      const double across_first = std::min(right(std::min(col, col2), row),
                                           down(col2, std::min(row, row2)));
      const double down_first = std::min(down(col, std::min(row, row2)),
                                         right(std::min(col, col2), row2));
      return 0.5 * (across_first + down_first);
    };
    std::vector<double> sum(n * num_labels, 0.0);
    for (const auto& [dx, dy] : std::vector<std::pair<int, int>>{
             {1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, -1}, {-1, 1}, {1, -1}}) {
      std::vector<double> path(n * num_labels, 0.0);
      // Rows and columns in the direction's order, so that each pixel's predecessor is done.
      for (int i = 0; i < height; ++i) {
        const int row = dy >= 0 ? i : height - 1 - i;
        for (int j = 0; j < width; ++j) {
          const int col = dx >= 0 ? j : width - 1 - j;
          const size_t p = static_cast<size_t>(row) * width + col;
          const int pc = col - dx, pr = row - dy;
          const bool has_previous = pc >= 0 && pc < width && pr >= 0 && pr < height;
          const size_t q = has_previous ? static_cast<size_t>(pr) * width + pc : 0;
          for (int b = 0; b < num_labels; ++b) {
            double value = problem.Cost(b, p);
            if (has_previous) {
              const double w = weight(pc, pr, dx, dy);
              double best = std::numeric_limits<double>::infinity(), lowest = best;
              for (int a = 0; a < num_labels; ++a) {
                const double d = static_cast<double>(problem.Value(q, a)) - problem.Value(p, b);
                best = std::min(best, path[a * n + q] +
                                          w * std::min(d * d, static_cast<double>(
                                                                  problem.truncation)));
                lowest = std::min(lowest, path[a * n + q]);
              }
              value += best - lowest;
            }
            path[b * n + p] = value;
            sum[b * n + p] += value;
          }
        }
      }
    }
    const std::vector<int> cpu = SolveSemiGlobalCpu(problem, 8);
    const std::vector<int> device = SolveSemiGlobalOpenCL(problem, 8, 0, Context().get());
    for (size_t p = 0; p < n; ++p) {
      double lowest = std::numeric_limits<double>::infinity();
      for (int b = 0; b < num_labels; ++b) lowest = std::min(lowest, sum[b * n + p]);
      EXPECT_LE(sum[cpu[p] * n + p], lowest + 1e-4) << "seed " << seed << " pixel " << p;
      EXPECT_LE(sum[device[p] * n + p], lowest + 1e-4) << "seed " << seed << " pixel " << p;
    }
  }
}

// Independent of the kernels' CPU copies: on a chain (a tree), min-sum belief propagation is
// exact, so the device's labels reach the dynamic programme's minimum; rows and columns, with
// label offsets and truncation.
TEST(BeliefPropagation, ExactOnAChain) {
  for (const auto& [width, height] : {std::pair<int, int>{14, 1}, std::pair<int, int>{1, 14}}) {
    for (bool offsets : {false, true}) {
      MrfProblem problem = RandomProblem(width, height, 6, 0.8f, 21 + width);
      if (offsets) {
        problem.truncation = 2.0f;
        problem.label_step = 0.5f;
        problem.label_offset.resize(problem.NumPixels());
        for (size_t p = 0; p < problem.NumPixels(); ++p) problem.label_offset[p] = 0.3f * (p % 4);
      }
      MrfSolverOptions options;
      options.solver = MrfSolverType::kBeliefPropagation;
      options.bp_iterations = 4 * static_cast<int>(problem.NumPixels());
      options.icm_polish_iterations = 0;
      const MrfResult result = SolveMrf(problem, options, Context().get());
      const double exact = ChainMinimum(problem);
      EXPECT_NEAR(result.energy, exact, 1e-5 * std::abs(exact))
          << width << " x " << height << (offsets ? ", offsets" : "");
    }
  }
}

// The device's solvers with their ICM polish end at a single-site minimum of the energy, as
// computed here independently, also on degenerate shapes (one pixel, one row, one column, two
// rows or columns) and label counts (1, 2).
TEST(MrfSolvers, IcmPolishEndsAtASingleSiteMinimum) {
  int seed = 40;
  for (const auto& [width, height] :
       {std::pair<int, int>{1, 1}, {40, 1}, {1, 40}, {33, 2}, {2, 33}, {9, 7}}) {
    for (int num_labels : {1, 2, 5}) {
      const MrfProblem problem = RandomProblem(width, height, num_labels, 0.6f, ++seed);
      for (MrfSolverType type : {MrfSolverType::kSemiGlobal, MrfSolverType::kBeliefPropagation}) {
        const MrfResult result = Solve(problem, type, Context().get(), 4, 200);
        ASSERT_EQ(result.labels.size(), problem.NumPixels());
        EXPECT_NEAR(result.energy, MrfEnergy(problem, result.labels),
                    1e-5 * std::max(1.0, std::abs(result.energy)));
        std::string where;
        EXPECT_TRUE(IsSingleSiteMinimum(problem, result.labels, &where))
            << ToString(type) << " " << width << " x " << height << ", " << num_labels
            << " labels: " << where;
      }
    }
  }
}

// The documented tie rules, where every label costs the same: the solvers pick the lowest
// label, and ICM (on the CPU and on the device) keeps the current one.
TEST(MrfSolvers, TiesGoToTheLowestLabelAndIcmKeepsTheCurrentOne) {
  MrfProblem problem;
  problem.width = 7;
  problem.height = 5;
  problem.num_labels = 4;
  problem.data_cost.assign(problem.NumPixels() * problem.num_labels, 0.5f);
  for (MrfSolverType type :
       {MrfSolverType::kSemiGlobal, MrfSolverType::kSemiGlobalCpu,
        MrfSolverType::kBeliefPropagation, MrfSolverType::kBeliefPropagationCpu,
        MrfSolverType::kWinnerTakeAll}) {
    const MrfResult result = Solve(problem, type, UsesOpenCL(type) ? Context().get() : nullptr);
    EXPECT_EQ(result.labels, std::vector<int>(problem.NumPixels(), 0)) << ToString(type);
  }
  std::vector<int> start(problem.NumPixels());
  for (size_t p = 0; p < start.size(); ++p) start[p] = static_cast<int>((p * 7) % 4);
  std::vector<int> cpu = start;
  PolishWithIcm(problem, 10, &cpu);
  EXPECT_EQ(cpu, start);
  OpenCLContext* context = Context().get();
  auto buffer = [&](const std::vector<float>& values) {
    return cl::Buffer(context->Context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR,
                      sizeof(float) * values.size(), const_cast<float*>(values.data()));
  };
  const std::vector<float> zeros(problem.NumPixels(), 0.0f);
  const cl::Buffer cost = buffer(problem.data_cost), offset = buffer(zeros),
                   weight_right = buffer(zeros), weight_down = buffer(zeros);
  std::vector<int> device = start;
  const cl::Buffer labels(context->Context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR,
                          sizeof(int) * device.size(), device.data());
  RunIcmOpenCL(context, cost, offset, weight_right, weight_down, problem, 10, labels);
  EXPECT_EQ(MrfReadLabels(context->Queue(), labels, device.size()), start);
}

// The checkerboard ICM kernel on its own equals PolishWithIcm, from winner-take-all labels, on
// a size that leaves a partial work-group (23 x 17), with truncation, label offsets and a
// fractional label step, and each lowers the energy.
TEST(Icm, OpenCLMatchesCpuReference) {
  for (const float truncation : {std::numeric_limits<float>::infinity(), 4.0f}) {
    // Label differences up to 6.5 (12 labels 0.5 apart, offsets up to 0.5): squared, past the
    // truncation.
    MrfProblem problem = RandomProblem(23, 17, 12, 0.6f, 11);
    problem.truncation = truncation;
    problem.label_step = 0.5f;
    problem.label_offset.resize(problem.NumPixels());
    for (size_t p = 0; p < problem.NumPixels(); ++p) problem.label_offset[p] = 0.013f * (p % 41);
    const std::vector<int> start = WinnerTakeAll(problem);
    std::vector<int> cpu = start;
    PolishWithIcm(problem, 30, &cpu);
    OpenCLContext* context = Context().get();
    auto buffer = [&](const std::vector<float>& values) {
      return cl::Buffer(context->Context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR,
                        sizeof(float) * values.size(), const_cast<float*>(values.data()));
    };
    const cl::Buffer cost = buffer(problem.data_cost), offset = buffer(problem.label_offset),
                     weight_right = buffer(problem.weight_right),
                     weight_down = buffer(problem.weight_down);
    std::vector<int> device = start;
    const cl::Buffer labels(context->Context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR,
                            sizeof(int) * device.size(), device.data());
    RunIcmOpenCL(context, cost, offset, weight_right, weight_down, problem, 30, labels);
    device = MrfReadLabels(context->Queue(), labels, device.size());
    int differing = 0;
    for (size_t p = 0; p < device.size(); ++p) differing += device[p] != cpu[p];
    EXPECT_EQ(differing, 0) << "truncation " << truncation;
    EXPECT_NE(cpu, start) << "truncation " << truncation;  // ICM had work to do
    EXPECT_LT(MrfEnergy(problem, cpu), MrfEnergy(problem, start)) << "truncation " << truncation;
  }
}

// The OpenCL belief propagation (with and without the ICM polish on the device) equals its
// CPU reference.
TEST(BeliefPropagation, OpenCLMatchesCpuReference) {
  for (int variant = 0; variant < 4; ++variant) {
    const int icm = variant == 3 ? 20 : 0;
    MrfProblem problem = variant == 0 ? RandomProblem(23, 17, 5, 0.5f, 5)
                                      : SyntheticStereoMrfProblem(24, 20, 12, 0.5f, 9);
    if (variant >= 2) {
      problem.truncation = 4.0f;
      problem.label_step = 0.25f;
      problem.label_offset.resize(problem.NumPixels());
      for (size_t p = 0; p < problem.NumPixels(); ++p) problem.label_offset[p] = 0.01f * (p % 37);
    }
    MrfSolverOptions options;
    options.bp_iterations = 12;
    options.icm_polish_iterations = icm;
    options.solver = MrfSolverType::kBeliefPropagationCpu;
    const MrfResult cpu = SolveMrf(problem, options, nullptr);
    options.solver = MrfSolverType::kBeliefPropagation;
    const MrfResult ocl = SolveMrf(problem, options, Context().get());
    int differing = 0;
    for (size_t p = 0; p < problem.NumPixels(); ++p) differing += cpu.labels[p] != ocl.labels[p];
    EXPECT_LE(std::abs(cpu.energy - ocl.energy), 1e-4 * std::abs(cpu.energy))
        << "variant " << variant << ": " << differing << " labels differ";
    EXPECT_EQ(differing, 0) << "variant " << variant;
    EXPECT_LT(cpu.energy, MrfEnergy(problem, WinnerTakeAll(problem)));
  }
}

// The OpenCL semi-global matching (with and without the ICM polish on the device) equals its
// CPU reference.
TEST(SemiGlobal, OpenCLMatchesCpuReference) {
  for (int num_directions : {4, 8}) {
    for (int variant = 0; variant < 4; ++variant) {
      const int icm = variant == 3 ? 20 : 0;
      MrfProblem problem = variant == 0 ? RandomProblem(23, 17, 5, 0.5f, 5)
                                        : SyntheticStereoMrfProblem(24, 20, 12, 0.5f, 9);
      if (variant >= 2) {
        problem.truncation = 4.0f;
        problem.label_step = 0.25f;
        problem.label_offset.resize(problem.NumPixels());
        for (size_t p = 0; p < problem.NumPixels(); ++p) {
          problem.label_offset[p] = 0.01f * (p % 37);
        }
      }
      const MrfResult cpu =
          Solve(problem, MrfSolverType::kSemiGlobalCpu, nullptr, num_directions, icm);
      const MrfResult ocl =
          Solve(problem, MrfSolverType::kSemiGlobal, Context().get(), num_directions, icm);
      int differing = 0;
      for (size_t p = 0; p < problem.NumPixels(); ++p) differing += cpu.labels[p] != ocl.labels[p];
      EXPECT_LE(std::abs(cpu.energy - ocl.energy), 1e-4 * std::abs(cpu.energy))
          << num_directions << " directions, variant " << variant << ": " << differing
          << " labels differ";
      EXPECT_EQ(differing, 0) << num_directions << " directions, variant " << variant;
    }
  }
}

}  // namespace
}  // namespace hairmvs
