#include "src/evaluation/evaluation_util.h"

#include <gtest/gtest.h>

#include <vector>

namespace hairmvs {
namespace {

TEST(EvaluationUtil, WeightedDistancesCountAsThatManyCopies) {
  const std::vector<double> distances = {0.004, 0.001, 0.003, 0.002};
  // Equal weights: exactly the plain figures (the median of an even count: the middle two's
  // mean).
  const DistanceStats plain = SummarizeDistances(distances);
  const DistanceStats equal = SummarizeDistances(distances, {2.5, 2.5, 2.5, 2.5});
  EXPECT_DOUBLE_EQ(equal.mean_mm, plain.mean_mm);
  EXPECT_DOUBLE_EQ(equal.median_mm, 2.5);
  EXPECT_DOUBLE_EQ(equal.median_mm, plain.median_mm);
  EXPECT_DOUBLE_EQ(equal.p90_mm, plain.p90_mm);
  // 1 mm standing for 5 of them (a view sampled at 1 in 5) and the others for 1: the mean and
  // median of 1, 1, 1, 1, 1, 2, 3, 4 mm.
  const DistanceStats weighted = SummarizeDistances(distances, {1, 5, 1, 1});
  EXPECT_EQ(weighted.count, 4);
  EXPECT_NEAR(weighted.mean_mm, 14.0 / 8, 1e-12);
  EXPECT_NEAR(weighted.median_mm, 1.0, 1e-12);
  EXPECT_NEAR(weighted.p90_mm, 3.0, 1e-12);  // the copy at index round(0.9 x 7) = 6
}

}  // namespace
}  // namespace hairmvs
