#include "src/orientation/filter_bank.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numeric>

namespace hairmvs {
namespace {

TEST(OrientationFilterBank, ZeroMeanSymmetricAndRotated) {
  OrientationFieldOptions options;  // the paper's filter: 0.5 / 1 px across, 4 px along
  options.sigma_across_inner_px = 0.5;
  options.sigma_across_outer_px = 1.0;
  const OrientationFilterBank bank(options);
  ASSERT_EQ(bank.NumOrientations(), 180);
  EXPECT_EQ(bank.Radius(), 12);  // 3 sigma_along
  for (int k = 0; k < bank.NumOrientations(); ++k) {
    double sum = 0;
    std::map<std::pair<int, int>, float> weights;
    for (const auto& tap : bank.Taps(k)) {
      sum += tap.weight;
      weights[{tap.dx, tap.dy}] = tap.weight;
    }
    EXPECT_NEAR(sum, 0.0, 1e-6) << "k=" << k;  // zero mean: flat regions respond 0
    for (const auto& [d, w] : weights) {
      const auto it = weights.find({-d.first, -d.second});
      ASSERT_NE(it, weights.end());
      EXPECT_EQ(it->second, w);  // K(-d) = K(d)
    }
    // The long axis points along theta: the tap at 5 px along the axis is positive, the one
    // 5 px across is not.
    const double t = bank.ThetaRad(k);
    const auto along = weights.find({static_cast<int>(std::lround(5 * std::cos(t))),
                                     static_cast<int>(std::lround(5 * std::sin(t)))});
    if (std::abs(5 * std::cos(t) - std::round(5 * std::cos(t))) < 0.1 &&
        std::abs(5 * std::sin(t) - std::round(5 * std::sin(t))) < 0.1) {
      ASSERT_NE(along, weights.end());
      EXPECT_GT(along->second, 0) << "k=" << k;
    }
    EXPECT_EQ(weights.count({static_cast<int>(std::lround(-5 * std::sin(t))),
                             static_cast<int>(std::lround(5 * std::cos(t)))}),
              0u)
        << "k=" << k;
  }
  // theta = 0: long axis along +x; theta = 90 degrees: along +y.
  auto weight_at = [&bank](int k, int dx, int dy) {
    for (const auto& tap : bank.Taps(k)) {
      if (tap.dx == dx && tap.dy == dy) return tap.weight;
    }
    return 0.0f;
  };
  EXPECT_GT(weight_at(0, 8, 0), 0);
  EXPECT_LT(weight_at(0, 0, 2), 0);
  EXPECT_GT(weight_at(90, 0, 8), 0);
  EXPECT_LT(weight_at(90, 2, 0), 0);
}

TEST(OrientationFilterBank, BlockedBankHoldsEveryTapOnce) {
  const OrientationFilterBank bank{OrientationFieldOptions()};
  for (int block_size : {1, 7, 12}) {
    const BlockedFilterBank blocked = MakeBlockedFilterBank(bank, block_size);
    ASSERT_EQ(blocked.num_blocks, (180 + block_size - 1) / block_size);
    // Rebuild each filter's response to a unit impulse at every tap from the pairs.
    for (int k = 0; k < bank.NumOrientations(); ++k) {
      const int b = k / block_size, j = k % block_size;
      std::map<std::pair<int, int>, float> rebuilt;
      for (int t = blocked.tap_begin[b]; t < blocked.tap_begin[b + 1]; ++t) {
        const float w = blocked.weights[t * block_size + j];
        if (w == 0) continue;
        rebuilt[{blocked.tap_dx[t], blocked.tap_dy[t]}] += w;
        rebuilt[{-blocked.tap_dx[t], -blocked.tap_dy[t]}] += w;
      }
      ASSERT_EQ(rebuilt.size(), bank.Taps(k).size()) << "k=" << k;
      for (const auto& tap : bank.Taps(k)) {
        EXPECT_EQ(rebuilt[std::make_pair(tap.dx, tap.dy)], tap.weight);
      }
    }
  }
}

TEST(OrientationFieldOptions, Check) {
  OrientationFieldOptions options;
  std::string error;
  EXPECT_TRUE(options.Check(&error));
  options.sigma_across_outer_px = 0.4;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("sigma_across_outer_px"), std::string::npos);
  options = OrientationFieldOptions();
  options.num_orientations = 1;
  EXPECT_FALSE(options.Check(&error));
  // Each sigma is named; a confidence exponent beyond 10 (every field underflowing to 0) too.
  const std::pair<double OrientationFieldOptions::*, std::string> sigmas[] = {
      {&OrientationFieldOptions::sigma_across_inner_px, "sigma_across_inner_px"},
      {&OrientationFieldOptions::sigma_across_outer_px, "sigma_across_outer_px"},
      {&OrientationFieldOptions::sigma_along_px, "sigma_along_px"}};
  for (const auto& [sigma, name] : sigmas) {
    options = OrientationFieldOptions();
    options.*sigma = 0;
    EXPECT_FALSE(options.Check(&error));
    EXPECT_NE(error.find(name + " must be > 0"), std::string::npos) << error;
  }
  options = OrientationFieldOptions();
  options.confidence_gamma = 10;
  EXPECT_TRUE(options.Check(&error)) << error;
  options.confidence_gamma = 10.5;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("confidence_gamma must be in (0, 10]"), std::string::npos) << error;
}

}  // namespace
}  // namespace hairmvs
