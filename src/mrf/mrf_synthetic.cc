#include "src/mrf/mrf_synthetic.h"

#include <cmath>
#include <random>

namespace hairmvs {

MrfProblem SyntheticStereoMrfProblem(int width, int height, int num_labels, float lambda,
                                     uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  MrfProblem problem;
  problem.width = width;
  problem.height = height;
  problem.num_labels = num_labels;
  const size_t n = problem.NumPixels();
  problem.data_cost.resize(n * num_labels);
  std::vector<float> theta(n);
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const size_t p = static_cast<size_t>(row) * width + col;
      const float x = (col + 0.5f) / width;
      const float y = (row + 0.5f) / height;
      const float r2 = (x - 0.5f) * (x - 0.5f) + (y - 0.5f) * (y - 0.5f);
      const float truth =
          (num_labels - 1) * (0.2f + 0.4f * x + 0.1f * y + 0.3f * std::exp(-r2 / 0.02f));
      const bool outlier = unit(rng) < 0.1f;
      for (int l = 0; l < num_labels; ++l) {
        const float d = l - truth;
        problem.data_cost[l * n + p] =
            outlier ? unit(rng) : std::min(0.25f * d * d, 1.0f) + 0.3f * unit(rng);
      }
      theta[p] = (x > 0.6f ? 1.2f : 0.2f) + 0.3f * y + 0.05f * unit(rng);
    }
  }
  problem.weight_right.assign(n, 0.0f);
  problem.weight_down.assign(n, 0.0f);
  auto weight = [&](size_t p, size_t q) {
    // |O(p) - O(q)| for unit complex orientations e^{2 i theta} (theta modulo pi).
    const float dre = std::cos(2 * theta[p]) - std::cos(2 * theta[q]);
    const float dim = std::sin(2 * theta[p]) - std::sin(2 * theta[q]);
    return lambda * std::exp(-(dre * dre + dim * dim) / (2 * 0.15f * 0.15f));
  };
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const size_t p = static_cast<size_t>(row) * width + col;
      if (col + 1 < width) problem.weight_right[p] = weight(p, p + 1);
      if (row + 1 < height) problem.weight_down[p] = weight(p, p + width);
    }
  }
  return problem;
}

}  // namespace hairmvs
