#include "src/orientation/filter_bank.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "src/core/logging.h"

namespace hairmvs {
namespace {

// A normalised 1D Gaussian: integrates to 1 over the real line.
double Gaussian(double t, double sigma) {
  return std::exp(-0.5 * t * t / (sigma * sigma)) / (std::sqrt(2.0 * M_PI) * sigma);
}

}  // namespace

bool OrientationFieldOptions::Check(std::string* error) const {
  auto fail = [error](const std::string& message) {
    if (error != nullptr) *error = message;
    return false;
  };
  if (num_levels < 1 || num_levels > kMaxLevels) {
    return fail("num_levels must be in [1, " + std::to_string(kMaxLevels) + "]");
  }
  if (num_orientations < 2 || num_orientations > 720)
    return fail("num_orientations must be in [2, 720]");
  if (!(sigma_across_inner_px > 0)) return fail("sigma_across_inner_px must be > 0");
  if (!(sigma_across_outer_px > 0)) return fail("sigma_across_outer_px must be > 0");
  if (!(sigma_along_px > 0)) return fail("sigma_along_px must be > 0");
  if (!(sigma_across_outer_px > sigma_across_inner_px))
    return fail("sigma_across_outer_px must exceed sigma_across_inner_px (a ridge detector)");
  // Beyond 10 the fields' magnitudes underflow to 0 in float: every field empty.
  if (!(confidence_gamma > 0 && confidence_gamma <= 10)) {
    return fail("confidence_gamma must be in (0, 10]");
  }
  if (!(min_positive_response_ratio >= 0 && min_positive_response_ratio < 1))
    return fail("min_positive_response_ratio must be in [0, 1)");
  if (filter_supersampling < 1 || filter_supersampling > 16)
    return fail("filter_supersampling must be in [1, 16]");
  if (!(truncation_sigmas >= 1 && truncation_sigmas <= 6))
    return fail("truncation_sigmas must be in [1, 6]");
  if (truncation_sigmas * std::max(sigma_along_px, sigma_across_outer_px) > 32)
    return fail("the filter support (truncation_sigmas * the larger of sigma_along_px and "
                "sigma_across_outer_px) must stay within 32 px");
  return true;
}

OrientationFilterBank::OrientationFilterBank(const OrientationFieldOptions& options) {
  std::string error;
  THROW_IF(!options.Check(&error), "OrientationField options: " << error);
  const double max_along = options.truncation_sigmas * options.sigma_along_px;
  const double max_across = options.truncation_sigmas * options.sigma_across_outer_px;
  // 1e-9: keep samples exactly on the truncation boundary whatever the rounding of cos/sin.
  const double eps = 1e-9;
  const int n = options.filter_supersampling;
  // Pixel squares reach 0.5 px (up to 0.71 px diagonally) beyond their centres.
  const int r = static_cast<int>(std::floor(std::max(max_along, max_across) + (n > 1 ? 1 : 0)));
  taps_.resize(options.num_orientations);
  for (int k = 0; k < options.num_orientations; ++k) {
    const double theta = M_PI * k / options.num_orientations;
    const double c = std::cos(theta);
    const double s = std::sin(theta);
    struct Sample {
      int dx, dy;
      double inner, outer;
    };
    std::vector<Sample> samples;
    double inner_sum = 0, outer_sum = 0;
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        // The tap's weight: the integral of the continuous filter over the part of the tap's
        // pixel square inside the support rectangle, from n x n samples (n = 1: the value at
        // the centre, i.e. point sampling). Clipping to the rectangle makes the taps tile it
        // exactly at every angle, so no angle gains or loses filter mass at the jagged edge
        // of the support: the gains of the 180 filters agree, which matters because the
        // response varies by well under 1% within a few degrees of its maximum.
        // Squares whose centre is more than 0.71 px (half a diagonal) outside cannot reach in.
        const double centre_along = dx * c + dy * s, centre_across = -dx * s + dy * c;
        if (std::abs(centre_along) > max_along + 0.71 ||
            std::abs(centre_across) > max_across + 0.71)
          continue;
        Sample sample{dx, dy, 0.0, 0.0};
        int inside = 0;
        for (int i = 0; i < n; ++i) {
          for (int j = 0; j < n; ++j) {
            const double sx = dx + (j + 0.5) / n - 0.5, sy = dy + (i + 0.5) / n - 0.5;
            const double along = sx * c + sy * s, across = -sx * s + sy * c;
            if (std::abs(along) > max_along + eps || std::abs(across) > max_across + eps) continue;
            ++inside;
            const double g_along = Gaussian(along, options.sigma_along_px);
            sample.inner += Gaussian(across, options.sigma_across_inner_px) * g_along / (n * n);
            sample.outer += Gaussian(across, options.sigma_across_outer_px) * g_along / (n * n);
          }
        }
        if (inside == 0) continue;
        inner_sum += sample.inner;
        outer_sum += sample.outer;
        samples.push_back(sample);
      }
    }
    // Zero mean: the truncated outer Gaussian loses more mass than the inner one (0.27% at
    // 3 sigma), which would give flat bright regions a small positive response.
    const double outer_scale = options.normalize_sampled_filters ? inner_sum / outer_sum : 1.0;
    for (const auto& sample : samples) {
      FilterTap tap;
      tap.dx = sample.dx;
      tap.dy = sample.dy;
      tap.weight = static_cast<float>(sample.inner - sample.outer * outer_scale);
      radius_ = std::max({radius_, std::abs(tap.dx), std::abs(tap.dy)});
      taps_[k].push_back(tap);
    }
  }
}

double OrientationFilterBank::ThetaRad(int k) const { return M_PI * k / NumOrientations(); }

BlockedFilterBank MakeBlockedFilterBank(const OrientationFilterBank& bank, int block_size) {
  CHECK_GE(block_size, 1);
  BlockedFilterBank blocked;
  blocked.block_size = block_size;
  blocked.num_orientations = bank.NumOrientations();
  blocked.num_blocks = (bank.NumOrientations() + block_size - 1) / block_size;
  blocked.tap_begin.push_back(0);
  for (int b = 0; b < blocked.num_blocks; ++b) {
    // (dx, dy) of the pair representative -> weight per angle of the block. std::map orders
    // the taps by row, then column, which keeps the kernel's loads walking through memory.
    std::map<std::pair<int, int>, std::vector<float>> pairs;
    for (int j = 0; j < block_size; ++j) {
      const int k = b * block_size + j;
      if (k >= bank.NumOrientations()) break;
      for (const auto& tap : bank.Taps(k)) {
        const bool representative = tap.dy > 0 || (tap.dy == 0 && tap.dx >= 0);
        if (!representative) continue;
        auto& w = pairs[{tap.dy, tap.dx}];
        if (w.empty()) w.assign(block_size, 0.0f);
        // The centre is loaded twice (I(p) + I(p)): halve its weight (exact in floating point).
        w[j] = (tap.dx == 0 && tap.dy == 0) ? 0.5f * tap.weight : tap.weight;
      }
    }
    for (const auto& [dydx, w] : pairs) {
      blocked.tap_dy.push_back(dydx.first);
      blocked.tap_dx.push_back(dydx.second);
      blocked.weights.insert(blocked.weights.end(), w.begin(), w.end());
    }
    blocked.tap_begin.push_back(static_cast<int>(blocked.tap_dx.size()));
  }
  return blocked;
}

}  // namespace hairmvs
