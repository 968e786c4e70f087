#include "src/stereo/depth_estimator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>

#include "hairmvs/orientation_fields.h"
#include "src/opencl/opencl_context.h"
#include "src/stereo/stereo_test_util.h"

namespace hairmvs {
namespace {

using testing_util::LookAtCamera;
using testing_util::MakeStrands;
using testing_util::MedianAbsError;
using testing_util::Pyramid;
using testing_util::RenderView;
using testing_util::Surface;

TEST(DepthEstimator, SubpixelOffsetsFollowEquation9) {
  // Three pixels, five labels: a parabola with its minimum at 2.3, a minimum at the lower
  // neighbour, and a label at the end of the range.
  const int n = 3, L = 5;
  std::vector<float> volume(n * L);
  for (int l = 0; l < L; ++l) {
    volume[l * n + 0] = static_cast<float>((l - 2.3) * (l - 2.3));
    volume[l * n + 1] = static_cast<float>(l);
    volume[l * n + 2] = 1.0f;
  }
  const std::vector<float> offsets = SubpixelOffsets(volume, n, L, {2, 2, 4});
  EXPECT_NEAR(offsets[0], 0.3f, 1e-5);
  EXPECT_FLOAT_EQ(offsets[1], -0.5f);
  EXPECT_FLOAT_EQ(offsets[2], 0.0f);
}

// lambda exp(-|O(p) - O(p')|^2 / (2 sigma_o^2)) per edge: differences in both channels, of a
// size whose square is neither 1 nor the size itself; 0 beyond the last column and row.
TEST(DepthEstimator, SmoothnessWeightsFollowEquation3) {
  FloatMap o(2, 2, 2);
  o.At(0, 0, 0) = 0.5f;
  o.At(0, 0, 1) = 0.1f;
  o.At(0, 1, 0) = 0.5f;  // the same as (0, 0)
  o.At(0, 1, 1) = 0.1f;
  o.At(1, 0, 0) = 0.2f;  // (0, 0) less (0.3, 0.4): |dO|^2 = 0.25
  o.At(1, 0, 1) = -0.3f;
  o.At(1, 1, 0) = 0.5f;  // (0, 1) less (0, 0.1): |dO|^2 = 0.01
  o.At(1, 1, 1) = 0.0f;
  const double sigma = 0.15;
  const auto weight = [&](double squared_difference) {
    return 2.0 * std::exp(-squared_difference / (2 * sigma * sigma));
  };
  std::vector<float> right, down;
  SmoothnessWeights(o, 2.0, sigma, &right, &down);
  ASSERT_EQ(right.size(), 4u);
  ASSERT_EQ(down.size(), 4u);
  EXPECT_FLOAT_EQ(right[0], 2.0f);
  EXPECT_NEAR(down[0], weight(0.25), 1e-6);
  EXPECT_NEAR(down[1], weight(0.01), 1e-6);
  EXPECT_NEAR(right[2], weight(0.18), 1e-6);  // (1, 0) to (1, 1): (0.3, 0.3)
  EXPECT_FLOAT_EQ(right[1], 0.0f);  // last column
  EXPECT_FLOAT_EQ(right[3], 0.0f);
  EXPECT_FLOAT_EQ(down[2], 0.0f);  // last row
  EXPECT_FLOAT_EQ(down[3], 0.0f);
}

struct Result {
  double median_abs_error_m = 0;
  double completeness = 0;
  size_t num_compared = 0;  // pixels with both a depth and a true depth
  double fine_energy = 0;  // the fine stage's MRF energy
  FloatMap coarse_data_term;  // with options.write_cost_volume
  FloatMap depth;
};

// The rendered grey picture as the 3-channel colour image the photometric cost matches.
FloatMap GreyToRgb(const FloatMap& gray) {
  FloatMap rgb(gray.Width(), gray.Height(), 3);
  for (int c = 0; c < 3; ++c) {
    std::copy(gray.Data().begin(), gray.Data().end(), rgb.Channel(c));
  }
  return rgb;
}

// Estimates the depth map of views[0] from the others over depth_min-depth_max (uniform in
// inverse depth), and compares it with `true_depth` on the pixels where the truth exists.
// `hull_entry`, `mask`: EstimateDepthMap's (empty: none).
Result EstimateAndCompare(const std::vector<StereoViewData>& views, const FloatMap& true_depth,
                          double depth_min, double depth_max,
                          const OrientationStereoOptions& options,
                          const FloatMap& hull_entry = FloatMap(),
                          const FloatMap& mask = FloatMap()) {
  std::vector<const StereoViewData*> sources;
  for (size_t i = 1; i < views.size(); ++i) sources.push_back(&views[i]);
  auto context = OpenCLContext::Create();
  const DepthLabels labels(depth_min, depth_max, options.num_depths, true);
  const DepthEstimate estimate = EstimateDepthMap(context.get(), views[0], sources, mask,
                                                  hull_entry, labels, options, nullptr);
  const size_t truth = std::count_if(true_depth.Data().begin(), true_depth.Data().end(),
                                     [](float d) { return d > 0; });
  Result result;
  result.median_abs_error_m = MedianAbsError(estimate.depth, true_depth, &result.num_compared);
  result.completeness = truth > 0 ? static_cast<double>(result.num_compared) / truth : 0;
  result.fine_energy = estimate.fine_energy;
  result.coarse_data_term = estimate.coarse_data_term.cost;
  result.depth = estimate.depth;
  return result;
}

// Renders the views, estimates the reference's depth map, compares with the truth on pixels
// where the truth exists.
// hull_margin_m > 0: a visual hull whose entry lies that far in front of the true depth at
// every pixel with one (none elsewhere). `mask`: the reference's (empty: none).
Result Reconstruct(const Surface& surface, const std::vector<StereoCamera>& cameras,
                   double depth_min, double depth_max, OrientationStereoOptions options,
                   unsigned seed, double hull_margin_m = 0, const FloatMap& mask = FloatMap()) {
  const auto strands = MakeStrands(surface, 900, surface.sphere ? 0.9 : 0.6, 0.25, seed);
  std::vector<StereoViewData> views;
  FloatMap true_depth;
  for (const StereoCamera& camera : cameras) {
    const testing_util::RenderedView view = RenderView(camera, surface, strands);
    if (true_depth.Empty()) true_depth = view.depth;
    views.push_back({camera, Pyramid(view.orientation, 3), {}, Pyramid(GreyToRgb(view.gray), 3)});
  }
  FloatMap hull_entry;
  if (hull_margin_m > 0) {
    hull_entry = FloatMap(true_depth.Width(), true_depth.Height(), 1);
    for (size_t p = 0; p < true_depth.Data().size(); ++p) {
      const float d = true_depth.Data()[p];
      if (d > 0) hull_entry.Data()[p] = d - static_cast<float>(hull_margin_m);
    }
  }
  return EstimateAndCompare(views, true_depth, depth_min, depth_max, options, hull_entry, mask);
}

OrientationStereoOptions TestOptions() {
  OrientationStereoOptions options;
  options.num_depths = 64;
  // 96 x 72 views: the coarse MRF on the half-size grid (level 2 would be 24 x 18).
  options.coarse_level = 1;
  // The rendered fields have |O| = 1 on strands (real ones are weaker): costs are about 10x
  // those of the shared sets, and the smoothness weight was chosen so, per label (unscaled:
  // these small views' labels step 1.15 px, against the 4 px at which lambda is given).
  options.lambda = 0.02;
  options.lambda_label_step_px = 0;
  // Windows 7/11/15 from fine to coarse: a 15 px window at level 0 spans a sixth of these
  // images, and its fronto-parallel bias shows on the sphere (10.6 mm median).
  options.window_px_level0 = 7;
  options.window_px_level2 = 15;
  return options;
}

// 96 x 72 views, f = 100 px, about 1 m away: one pixel of disparity over the 0.3 m baselines
// is about 30 mm of depth, so the tolerances below are about 0.3 px.
std::vector<StereoCamera> TCameras(const Eigen::Vector3d& target, double roll_rad = 0) {
  return {LookAtCamera({0, 0, 0}, target, 100, 96, 72),
          LookAtCamera({0.3, 0, 0}, target, 100, 96, 72, roll_rad),
          LookAtCamera({-0.3, 0, 0}, target, 100, 96, 72),
          LookAtCamera({0, -0.3, 0}, target, 100, 96, 72)};
}

// A plane 1 m in front of the reference, turned 0.35 rad about the vertical, reconstructed from
// the T cameras with `options`.
Result ReconstructTiltedPlane(const OrientationStereoOptions& options) {
  Surface plane;
  plane.point = {0, 0, 1};
  plane.normal = Eigen::Vector3d(std::sin(0.35), 0, -std::cos(0.35));
  return Reconstruct(plane, TCameras({0, 0, 1}), 0.7, 1.5, options, 1);
}

// The MRF weighs the smoothness with the view's scaled lambda: lambda at a label step s is the
// same estimate as the unscaled ViewLambda(the view's step); without the scaling, another.
TEST(DepthEstimator, TheMrfUsesTheViewsScaledLambda) {
  OrientationStereoOptions scaled = TestOptions();
  scaled.lambda_label_step_px = 0.5;
  const double step =
      LabelStepPxPerRadian(TCameras({0, 0, 1})[0], DepthLabels(0.7, 1.5, scaled.num_depths, true));
  OrientationStereoOptions unscaled = scaled;
  unscaled.lambda = scaled.ViewLambda(step);
  unscaled.lambda_label_step_px = 0;
  EXPECT_GT(unscaled.lambda, 4 * scaled.lambda);  // a step of about 1.15 px
  const Result a = ReconstructTiltedPlane(scaled), b = ReconstructTiltedPlane(unscaled);
  EXPECT_EQ(a.depth.Data(), b.depth.Data());
  EXPECT_EQ(a.fine_energy, b.fine_energy);
  OrientationStereoOptions plain = scaled;
  plain.lambda_label_step_px = 0;
  EXPECT_NE(ReconstructTiltedPlane(plain).fine_energy, a.fine_energy);
}

TEST(DepthEstimator, RecoversATiltedPlaneCoveredInStrands) {
  const Result result = ReconstructTiltedPlane(TestOptions());
  std::printf("plane: median |error| %.4f m, completeness %.3f\n", result.median_abs_error_m,
              result.completeness);
  EXPECT_LT(result.median_abs_error_m, 0.01);
  EXPECT_GT(result.completeness, 0.8);
}

// crop_to_mask: the estimate on the mask's box (with its margin) has the whole image's data
// term inside the mask, the same depths up to the MRF's paths, and nothing outside the mask.
TEST(DepthEstimator, CropToTheMaskKeepsTheWholeImagesDataTermAndDepths) {
  OrientationStereoOptions options = TestOptions();
  // Small windows, so that the box and its margin (twice the farthest reach, 8 level-0 px at
  // level 2) fit inside these 96 x 72 views: a crop of 64 x 64 px (48 x 48 rounded up to
  // multiples of 32, moved back from the bottom edge).
  options.window_px_level0 = 3;
  options.window_px_level1 = 3;
  options.window_px_level2 = 3;
  options.write_cost_volume = true;
  FloatMap mask(96, 72, 1);
  for (int row = 28; row < 44; ++row) {
    for (int col = 40; col < 56; ++col) mask.At(row, col) = 1.0f;
  }
  Surface plane;
  plane.point = {0, 0, 1};
  plane.normal = Eigen::Vector3d(std::sin(0.35), 0, -std::cos(0.35));
  const Result cropped = Reconstruct(plane, TCameras({0, 0, 1}), 0.7, 1.5, options, 1, 0, mask);
  options.crop_to_mask = false;
  const Result whole = Reconstruct(plane, TCameras({0, 0, 1}), 0.7, 1.5, options, 1, 0, mask);
  ASSERT_EQ(cropped.depth.Width(), 96);
  ASSERT_EQ(cropped.depth.Height(), 72);
  ASSERT_EQ(cropped.coarse_data_term.Width(), whole.coarse_data_term.Width());
  ASSERT_EQ(cropped.coarse_data_term.Channels(), options.num_depths);
  // The data term on the coarse (level 1) pixels inside the mask.
  double largest_cost = 0, largest_difference = 0;
  for (int row = 14; row < 22; ++row) {
    for (int col = 20; col < 28; ++col) {
      for (int k = 0; k < options.num_depths; ++k) {
        const float c = whole.coarse_data_term.At(row, col, k);
        largest_cost = std::max(largest_cost, std::abs(static_cast<double>(c)));
        const double difference = cropped.coarse_data_term.At(row, col, k) - c;
        largest_difference = std::max(largest_difference, std::abs(difference));
      }
    }
  }
  EXPECT_GT(largest_cost, 0.0);
  EXPECT_LE(largest_difference, 1e-5 * largest_cost);
  // It did crop: these fields are not masked, so the whole image has a data term at the
  // corner, the crop none.
  double corner_whole = 0, corner_cropped = 0;
  for (int k = 0; k < options.num_depths; ++k) {
    corner_whole += std::abs(whole.coarse_data_term.At(2, 2, k));
    corner_cropped += std::abs(cropped.coarse_data_term.At(2, 2, k));
  }
  EXPECT_GT(corner_whole, 0.0);
  EXPECT_EQ(corner_cropped, 0.0);
  int inside = 0, close = 0;
  for (int row = 0; row < 72; ++row) {
    for (int col = 0; col < 96; ++col) {
      const float c = cropped.depth.At(row, col), w = whole.depth.At(row, col);
      if (mask.At(row, col) == 0) {
        EXPECT_EQ(c, 0.0f) << row << " " << col;
        EXPECT_EQ(w, 0.0f) << row << " " << col;
        continue;
      }
      ++inside;
      close += c > 0 && w > 0 && std::abs(c - w) < 0.002f;
    }
  }
  std::printf("crop to the mask: %d of %d masked depths within 2 mm of the whole image's; median "
              "|error| %.4f m (whole image %.4f m)\n",
              close, inside, cropped.median_abs_error_m, whole.median_abs_error_m);
  EXPECT_GT(close, inside * 9 / 10);
  EXPECT_LT(cropped.median_abs_error_m, 0.01);
}

// The coarse stage without level 0 (coarse_first_level 1, a speed option) still finds the
// plane: the fine stage, with every level, refines what the coarser levels located.
TEST(DepthEstimator, CoarseStageWithoutTheFinestLevelStillRecoversThePlane) {
  OrientationStereoOptions options = TestOptions();
  options.coarse_first_level = 1;
  const Result result = ReconstructTiltedPlane(options);
  const Result all_levels = ReconstructTiltedPlane(TestOptions());
  std::printf("plane, coarse stage from level 1: median |error| %.4f m (all levels %.4f m), "
              "completeness %.3f\n",
              result.median_abs_error_m, all_levels.median_abs_error_m, result.completeness);
  EXPECT_LT(result.median_abs_error_m, 0.01);
  EXPECT_GT(result.completeness, 0.8);
  EXPECT_NE(result.median_abs_error_m, all_levels.median_abs_error_m);  // level 0 was left out
}

// The coarse stage's data term is the sum of the levels from coarse_first_level on, each
// scaled so that the levels used count for the paper's three: with one weight per level
// (level0_weight_angle_deg 0), levels 1 and 2 give 1.5 (L1 + L2), level 2 alone 3 L2 and level 1
// alone (num_levels 2) 3 L1, so the first is the mean of the other two. Dropping the coarsest
// level rather than the finest, or scaling by the count of all levels, breaks that.
TEST(DepthEstimator, CoarseDataTermSumsTheLevelsFromCoarseFirstLevelOn) {
  OrientationStereoOptions options = TestOptions();
  options.coarse_level = 2;  // a 24 x 18 grid, so that coarse_first_level may be 2
  options.level0_weight_angle_deg = 0;
  options.write_cost_volume = true;
  const auto coarse_term = [&](int num_levels, int first_level) {
    OrientationStereoOptions o = options;
    o.num_levels = num_levels;
    o.coarse_first_level = first_level;
    return ReconstructTiltedPlane(o).coarse_data_term;
  };
  const FloatMap all = coarse_term(3, 0), levels12 = coarse_term(3, 1),
                 level2 = coarse_term(3, 2), level1 = coarse_term(2, 1);
  ASSERT_EQ(levels12.Width(), 24);
  ASSERT_EQ(levels12.Height(), 18);
  ASSERT_EQ(levels12.Channels(), options.num_depths);
  double largest = 0, largest_difference = 0, largest_from_all = 0;
  for (size_t i = 0; i < levels12.Data().size(); ++i) {
    const double expected = 0.5 * (level1.Data()[i] + level2.Data()[i]);
    largest = std::max(largest, std::abs(expected));
    largest_difference =
        std::max(largest_difference, std::abs(levels12.Data()[i] - expected));
    largest_from_all =
        std::max(largest_from_all, std::abs(static_cast<double>(all.Data()[i]) - expected));
  }
  EXPECT_GT(largest, 0.0);
  EXPECT_LE(largest_difference, 1e-5 * largest);
  EXPECT_GT(largest_from_all, 0.05 * largest);  // level 0 counts when coarse_first_level is 0
}

// A data term of level 0 alone (num_levels 1) is still solved coarse to fine, on the grid of
// coarse_level, which the pyramid reaches whatever num_levels: the coarse data term has the
// grid's size, the fine stage runs, and the plane is found.
TEST(DepthEstimator, OneLevelDataTermIsStillSolvedCoarseToFine) {
  OrientationStereoOptions options = TestOptions();  // coarse_level 1: a 48 x 36 grid
  options.num_levels = 1;
  options.write_cost_volume = true;
  EXPECT_EQ(options.PyramidLevels(), 2);
  const Result result = ReconstructTiltedPlane(options);
  std::printf("plane, level 0 alone: median |error| %.4f m, completeness %.3f\n",
              result.median_abs_error_m, result.completeness);
  EXPECT_EQ(result.coarse_data_term.Width(), 48);
  EXPECT_EQ(result.coarse_data_term.Height(), 36);
  EXPECT_NE(result.fine_energy, 0);  // the fine stage ran (costs are negative: so is it)
  EXPECT_LT(result.median_abs_error_m, 0.01);
  EXPECT_GT(result.completeness, 0.8);
  // Single stage: the whole grid, no fine stage.
  options.coarse_level = -1;
  EXPECT_EQ(options.PyramidLevels(), 1);
  const Result single = ReconstructTiltedPlane(options);
  EXPECT_EQ(single.coarse_data_term.Width(), 96);
  EXPECT_EQ(single.fine_energy, 0);
}

// --OrientationStereo.mrf_icm_polish_iterations reaches the solver: without the ICM polish
// the semi-global labels keep a higher energy, and the plane is still recovered.
TEST(DepthEstimator, IcmPolishLowersTheEnergyOfTheSemiGlobalLabels) {
  OrientationStereoOptions options = TestOptions();
  options.mrf_icm_polish_iterations = 0;
  const Result without = ReconstructTiltedPlane(options);
  const Result with = ReconstructTiltedPlane(TestOptions());
  std::printf("plane: fine energy %.6g with 10 ICM sweeps, %.6g without; median %.4f / %.4f m\n",
              with.fine_energy, without.fine_energy, with.median_abs_error_m,
              without.median_abs_error_m);
  EXPECT_LT(with.fine_energy, without.fine_energy);
  EXPECT_LT(without.median_abs_error_m, 0.01);
}

TEST(DepthEstimator, RecoversASphereCoveredInStrands) {
  Surface sphere;
  sphere.sphere = true;
  sphere.point = {0, 0, 1.2};
  sphere.radius = 0.45;
  const Result result = Reconstruct(sphere, TCameras({0, 0, 1}), 0.6, 1.4, TestOptions(), 2);
  std::printf("sphere: median |error| %.4f m, completeness %.3f\n", result.median_abs_error_m,
              result.completeness);
  EXPECT_LT(result.median_abs_error_m, 0.01);
  EXPECT_GT(result.completeness, 0.5);
}

// Coarse labels from the visual hull (and the strands' plane from its tilt): with the default
// windows (15 px at level 0, a sixth of these images), aggregating at one depth behind a hull
// 20 mm in front of the sphere removes most of the fronto-parallel windows' bias (measured:
// 2.8 -> 1.0 mm median); a hull 150 mm in front (one T group's) still lets the labels reach
// the sphere (2.0 mm).
TEST(DepthEstimator, CoarseLabelsFromTheVisualHullFollowTheSphere) {
  Surface sphere;
  sphere.sphere = true;
  sphere.point = {0, 0, 1.2};
  sphere.radius = 0.45;
  OrientationStereoOptions options = TestOptions();
  options.window_px_level0 = 15;
  options.window_px_level2 = 7;
  options.final_guided_filter = false;  // a 15 px box over the depths biases it too
  auto reconstruct = [&](bool from_hull, double margin_m) {
    options.coarse_labels_from_visual_hull = from_hull;
    options.strand_plane_from_visual_hull = from_hull;
    return Reconstruct(sphere, TCameras({0, 0, 1}), 0.6, 1.4, options, 2, margin_m);
  };
  const Result fronto_parallel = reconstruct(false, 0.02);
  const Result tight = reconstruct(true, 0.02);
  const Result loose = reconstruct(true, 0.15);
  std::printf("sphere, 15 px windows: median |error| %.4f m fronto-parallel, %.4f m from a hull "
              "20 mm in front, %.4f m from one 150 mm in front; completeness %.3f / %.3f / %.3f\n",
              fronto_parallel.median_abs_error_m, tight.median_abs_error_m,
              loose.median_abs_error_m, fronto_parallel.completeness, tight.completeness,
              loose.completeness);
  EXPECT_LT(tight.median_abs_error_m, 0.6 * fronto_parallel.median_abs_error_m);
  EXPECT_LT(loose.median_abs_error_m, 0.01);
  EXPECT_GT(tight.completeness, 0.5);
  EXPECT_GT(loose.completeness, 0.5);
  // The coarse smoothness on the offsets behind the tight hull: the sphere is recovered, and
  // differently (the option reaches the MRF).
  options.coarse_smoothness_along_visual_hull = true;
  const Result along = reconstruct(true, 0.02);
  std::printf("sphere, smoothness along the hull: median |error| %.4f m, completeness %.3f\n",
              along.median_abs_error_m, along.completeness);
  EXPECT_LT(along.median_abs_error_m, 0.6 * fronto_parallel.median_abs_error_m);
  EXPECT_GT(along.completeness, 0.5);
  EXPECT_NE(along.fine_energy, tight.fine_energy);
}

// Check() refuses `options`, naming `option` in its message.
void ExpectRefusedNaming(const OrientationStereoOptions& options, const std::string& option) {
  std::string error;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find(option), std::string::npos) << error;
}

// The matching's normalisation and the confidence filter: a negative window radius, an eps
// that is not positive (a window of one valid pixel has variance 0: the scale would be
// infinite) and a negative confidence threshold are refused by name.
TEST(OrientationStereoOptions, NormalizationAndConfidenceOptions) {
  OrientationStereoOptions options;
  options.orientation_normalization_radius_px = -1;
  ExpectRefusedNaming(options, "orientation_normalization_radius_px");
  for (double eps : {0.0, -1e-3}) {
    options = OrientationStereoOptions();
    options.orientation_normalization_eps = eps;
    ExpectRefusedNaming(options, "orientation_normalization_eps");
  }
  options = OrientationStereoOptions();
  options.min_confidence = -0.5;
  ExpectRefusedNaming(options, "min_confidence");
  options = OrientationStereoOptions();
  options.orientation_normalization_radius_px = 0;  // the paper's raw fields
  std::string error;
  EXPECT_TRUE(options.Check(&error)) << error;
  // The pyramid the fields are computed with: refused here, by the options given, rather than
  // later by the orientation fields' own num_levels, which the user did not set.
  options = OrientationStereoOptions();
  options.coarse_level = OrientationFieldOptions::kMaxLevels;
  ExpectRefusedNaming(options, "coarse_level + 1 must be at most 8");
  options = OrientationStereoOptions();
  options.num_levels = OrientationFieldOptions::kMaxLevels + 1;
  ExpectRefusedNaming(options, "num_levels");
}

// The defaults pass Check; a strand plane tilted 90 degrees or more (or less than 0) and a
// photometric weight outside [0, 1], fewer than one round of the geometric pass and a view angle
// outside [0, 180] degrees are refused by name. The strands' plane follows the hull
// only for the costs that match orientations, through the plane homography.
TEST(OrientationStereoOptions, StrandPlaneOptions) {
  OrientationStereoOptions options;
  std::string error;
  EXPECT_TRUE(options.Check(&error)) << error;
  EXPECT_TRUE(options.StrandPlaneFromVisualHull());
  for (double tilt : {90.0, -1.0}) {
    options.max_strand_plane_tilt_deg = tilt;
    ExpectRefusedNaming(options, "max_strand_plane_tilt_deg");
  }
  options = OrientationStereoOptions();
  options.cost = StereoCost::kPhotometric;
  EXPECT_FALSE(options.StrandPlaneFromVisualHull());
  options.cost = StereoCost::kCombined;
  EXPECT_TRUE(options.StrandPlaneFromVisualHull());
  options.photometric_weight = 0.25;  // the combined data term's two costs and their shares
  const std::vector<std::pair<StereoCost, float>> terms = {{StereoCost::kOrientation, 0.75f},
                                                           {StereoCost::kPhotometric, 0.25f}};
  EXPECT_EQ(options.DataTerms(), terms);
  for (double weight : {-0.1, 1.1}) {
    options.photometric_weight = weight;
    ExpectRefusedNaming(options, "photometric_weight");
  }
  options = OrientationStereoOptions();
  options.geom_consistency_iterations = 0;
  ExpectRefusedNaming(options, "geom_consistency_iterations");
  // Weights that overflow the MRF's float costs (inf, or 0 * inf = NaN for sigma_o): each
  // had run a view and failed inside the MRF, or written empty maps, without naming it.
  for (const auto& [edit, name] :
       std::vector<std::pair<std::function<void(OrientationStereoOptions*)>, std::string>>{
           {[](OrientationStereoOptions* o) { o->lambda = 1e39; }, "lambda must be in [0, 1e6]"},
           {[](OrientationStereoOptions* o) { o->sigma_o = 1e-200; },
            "sigma_o must be in [1e-6, 1e6]"},
           {[](OrientationStereoOptions* o) { o->geom_prior_weight = 1e39; },
            "geom_prior_weight must be in [0, 1e6]"}}) {
    options = OrientationStereoOptions();
    edit(&options);
    ExpectRefusedNaming(options, name);
  }
  options = OrientationStereoOptions();
  options.geom_consistency_min_inconsistent_fraction = 1.5;
  ExpectRefusedNaming(options, "geom_consistency_min_inconsistent_fraction");
  options = OrientationStereoOptions();
  options.geom_consistency_min_gain = -2;
  ExpectRefusedNaming(options, "geom_consistency_min_gain");
  for (double angle : {-1.0, 181.0}) {
    options = OrientationStereoOptions();
    options.geom_consistency_max_view_angle_deg = angle;
    ExpectRefusedNaming(options, "geom_consistency_max_view_angle_deg");
  }
  options = OrientationStereoOptions();
  options.geom_consistency_max_num_views = -1;
  ExpectRefusedNaming(options, "geom_consistency_max_num_views");
  // Upper bounds on sizes and counts (beyond them a run ran out of memory mid-view, or every
  // map came out empty), and a fine band wider than the whole range.
  const std::vector<std::pair<std::function<void(OrientationStereoOptions*)>, std::string>>
      bounds = {
          {[](OrientationStereoOptions* o) { o->num_depths = 4097; },
           "num_depths must be in [3, 4096]"},
          {[](OrientationStereoOptions* o) { o->fine_num_labels = 257; },
           "fine_num_labels must be in [3, 256]"},
          {[](OrientationStereoOptions* o) { o->fine_label_step = 8.5; },
           "the fine band ((fine_num_labels - 1) x fine_label_step = 127.5 coarse labels) must "
           "not span more than the whole range (num_depths - 1 = 127)"},
          {[](OrientationStereoOptions* o) { o->orientation_normalization_radius_px = 256; },
           "orientation_normalization_radius_px must be in [0, 255]"},
          {[](OrientationStereoOptions* o) { o->visual_hull_mask_dilation_px = 256; },
           "visual_hull_mask_dilation_px must be in [0, 255]"},
          {[](OrientationStereoOptions* o) { o->guide_rms = 1e30; },
           "guide_rms must be in [0, 1000]"},
          {[](OrientationStereoOptions* o) { o->window_px_level1 = 0; },
           "window_px_level1 must be odd, in [1, 511]"},
          // Centred windows: an even width worked as the next odd one without a word.
          {[](OrientationStereoOptions* o) { o->window_px_level0 = 14; },
           "window_px_level0 must be odd, in [1, 511]"},
          {[](OrientationStereoOptions* o) { o->ncc_window_px = 8; },
           "ncc_window_px must be odd, in [1, 511]"},
          {[](OrientationStereoOptions* o) { o->ncc_window_px = 100001; },
           "ncc_window_px must be odd, in [1, 511]"},
          // Taken as "automatic" without a word, where colmap refuses it.
          {[](OrientationStereoOptions* o) { o->depth_min = -3; },
           "depth_min must be > 0, or 0 or -1 (automatic)"},
          {[](OrientationStereoOptions* o) { o->depth_max = -0.5; },
           "depth_max must be > 0, or 0 or -1 (automatic)"},
          // Beyond the coarse grid's level it was clamped to it without a word.
          {[](OrientationStereoOptions* o) { o->coarse_first_level = 3; },
           "coarse_first_level must be at most coarse_level and below num_levels"}};
  for (const auto& [edit, expected] : bounds) {
    options = OrientationStereoOptions();
    edit(&options);
    ExpectRefusedNaming(options, expected);
  }
  options = OrientationStereoOptions();
  options.fine_label_step = 127.0 / 15;  // 15 steps span the 127 of the whole range: allowed
  EXPECT_TRUE(options.Check(&error)) << error;
  options.coarse_level = -1;  // single stage: no fine band nor coarse levels to check
  options.fine_label_step = 100;
  options.coarse_first_level = 3;
  EXPECT_TRUE(options.Check(&error)) << error;
  options = OrientationStereoOptions();
  options.coarse_first_level = 2;  // the coarse grid's own level: allowed
  EXPECT_TRUE(options.Check(&error)) << error;
  options = OrientationStereoOptions();
  options.orientation_transfer = OrientationTransfer::kEpipoleRoll;
  EXPECT_FALSE(options.StrandPlaneFromVisualHull());
  options = OrientationStereoOptions();
  options.strand_plane_from_visual_hull = false;
  EXPECT_FALSE(options.StrandPlaneFromVisualHull());
}

// Level 0's weight per source: (angle_deg / view angle)^power clamped to [1/4, 4] against 1
// for the coarser levels, the levels averaging 1; 1 everywhere when off or with one level.
TEST(OrientationStereoOptions, LevelSourceWeightsFollowTheViewAngle) {
  OrientationStereoOptions options;
  options.level0_weight_angle_deg = 20;
  options.level0_weight_angle_power = 2;
  for (int l = 0; l < 3; ++l) EXPECT_NEAR(options.LevelSourceWeight(l, 3, 20.0), 1.0, 1e-12);
  // 14.14 degrees: level 0 x 2 (of 4 / 3 in all): 1.5, then 0.75 and 0.75.
  const double narrow = 20.0 / std::sqrt(2.0);
  EXPECT_NEAR(options.LevelSourceWeight(0, 3, narrow), 1.5, 1e-9);
  EXPECT_NEAR(options.LevelSourceWeight(1, 3, narrow), 0.75, 1e-9);
  EXPECT_NEAR(options.LevelSourceWeight(2, 3, narrow), 0.75, 1e-9);
  // 80 degrees: (1/4)^2 clamped to 1/4; 0 degrees: 4.
  EXPECT_NEAR(options.LevelSourceWeight(0, 3, 80.0), 0.25 / 0.75, 1e-9);
  EXPECT_NEAR(options.LevelSourceWeight(0, 3, 0.0), 2.0, 1e-9);
  for (double angle : {0.0, 7.0, 35.0, 80.0}) {
    double sum = 0;
    for (int l = 0; l < 3; ++l) sum += options.LevelSourceWeight(l, 3, angle);
    EXPECT_NEAR(sum, 3.0, 1e-9) << angle;
    EXPECT_NEAR(options.LevelSourceWeight(0, 1, angle), 1.0, 1e-12) << angle;
  }
  options.level0_weight_angle_deg = 0;  // the paper's equal levels
  EXPECT_NEAR(options.LevelSourceWeight(0, 3, 7.0), 1.0, 1e-12);
  options.level0_weight_angle_deg = -1;
  ExpectRefusedNaming(options, "level0_weight_angle_deg");
  options = OrientationStereoOptions();
  options.level0_weight_angle_power = 0;
  ExpectRefusedNaming(options, "level0_weight_angle_power");
}

// A block holds slice_block slices unless its largest buffer would not fit the device's largest
// allocation; never fewer than 1 nor more than the labels.
TEST(DepthEstimator, SliceBlockFitsTheLargestAllocation) {
  EXPECT_EQ(SliceBlockThatFits(8, 128, 1000, 1 << 20), 8);
  EXPECT_EQ(SliceBlockThatFits(8, 5, 1000, 1 << 20), 5);
  EXPECT_EQ(SliceBlockThatFits(8, 128, 1000, 5999), 5);
  EXPECT_EQ(SliceBlockThatFits(8, 128, 1000, 999), 1);
  EXPECT_EQ(SliceBlockThatFits(0, 128, 1000, 1 << 20), 1);
  // 24 Mpixel without a mask, the orientation cost's 3 planes: 8 slices take 2.1 GiB; a GPU of
  // 8 GiB whose largest allocation is 2 GiB gets 7.
  const size_t planes = sizeof(float) * 3 * size_t{6000} * 4000;
  EXPECT_GT(8 * planes, size_t{2} << 30);
  EXPECT_EQ(SliceBlockThatFits(8, 128, planes, size_t{2} << 30), 7);
}

// Each view's lambda is scaled by the square of its labels' step against lambda_label_step_px;
// as given when that is 0 or the view has no step.
TEST(OrientationStereoOptions, ViewLambdaFollowsTheLabelStep) {
  OrientationStereoOptions options;
  options.lambda = 0.2;
  options.lambda_label_step_px = 4;
  EXPECT_NEAR(options.ViewLambda(4.0), 0.2, 1e-12);
  EXPECT_NEAR(options.ViewLambda(2.0), 0.05, 1e-12);
  EXPECT_NEAR(options.ViewLambda(12.0), 1.8, 1e-12);
  EXPECT_NEAR(options.ViewLambda(0.0), 0.2, 1e-12);
  options.lambda_label_step_px = 0;
  EXPECT_NEAR(options.ViewLambda(2.0), 0.2, 1e-12);
  options.lambda_label_step_px = -1;
  ExpectRefusedNaming(options, "lambda_label_step_px");
  options.lambda_label_step_px = 1e-30;  // would scale lambda past any float weight
  ExpectRefusedNaming(options, "lambda_label_step_px");
  // The scaled weight stays within lambda's own bound.
  options.lambda = 1e6;
  options.lambda_label_step_px = 0.01;
  EXPECT_EQ(options.ViewLambda(1000.0), 1e6);
}

// The combined cost's data term is the weighted sum of the orientation and photometric costs'
// (each aggregated alike), and it recovers the tilted plane as each of them does.
TEST(DepthEstimator, CombinedCostIsTheWeightedSumOfTheTwoCosts) {
  OrientationStereoOptions options = TestOptions();
  options.write_cost_volume = true;
  const Result orientation = ReconstructTiltedPlane(options);
  options.cost = StereoCost::kPhotometric;
  const Result photometric = ReconstructTiltedPlane(options);
  options.cost = StereoCost::kCombined;
  options.photometric_weight = 0.3;
  const Result combined = ReconstructTiltedPlane(options);
  std::printf("tilted plane: median |error| orientation %.4f, photometric %.4f, combined %.4f m\n",
              orientation.median_abs_error_m, photometric.median_abs_error_m,
              combined.median_abs_error_m);
  const std::vector<float>& o = orientation.coarse_data_term.Data();
  const std::vector<float>& p = photometric.coarse_data_term.Data();
  const std::vector<float>& c = combined.coarse_data_term.Data();
  ASSERT_FALSE(c.empty());
  ASSERT_EQ(c.size(), o.size());
  ASSERT_EQ(c.size(), p.size());
  double max_difference = 0, max_cost = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    max_difference = std::max(max_difference, std::abs(c[i] - (0.7 * o[i] + 0.3 * p[i])));
    max_cost = std::max({max_cost, std::abs(static_cast<double>(o[i])),
                         std::abs(static_cast<double>(p[i]))});
  }
  EXPECT_GT(max_cost, 0.1);
  EXPECT_LT(max_difference, 1e-4 * max_cost);
  for (const Result* result : {&orientation, &photometric, &combined}) {
    EXPECT_LT(result->median_abs_error_m, 0.015);
    EXPECT_GT(result->completeness, 0.8);
  }
}

// best_source_fraction: per coarse label and pixel the data term is the sum of the lowest
// aggregated costs among the sources (here the best 2 of 3, scaled by 3 / 2), each source's
// cost as it is alone; Check refuses a fraction outside (0, 1].
TEST(DepthEstimator, BestSourcesSumTheLowestCostsPerPixelAndDepth) {
  Surface plane;
  plane.point = {0, 0, 1};
  plane.normal = Eigen::Vector3d(std::sin(0.35), 0, -std::cos(0.35));
  const std::vector<StereoCamera> cameras = TCameras({0, 0, 1});
  OrientationStereoOptions options = TestOptions();
  options.write_cost_volume = true;
  std::vector<std::vector<float>> alone;
  for (size_t s = 1; s < cameras.size(); ++s) {
    alone.push_back(
        Reconstruct(plane, {cameras[0], cameras[s]}, 0.7, 1.5, options, 1).coarse_data_term.Data());
  }
  options.best_source_fraction = 2.0 / 3;
  EXPECT_EQ(options.NumBestSources(3), 2);
  const Result best = Reconstruct(plane, cameras, 0.7, 1.5, options, 1);
  const std::vector<float>& got = best.coarse_data_term.Data();
  ASSERT_EQ(got.size(), alone[0].size());
  double max_difference = 0, max_cost = 0;
  size_t differs_from_sum = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    std::array<float, 3> c = {alone[0][i], alone[1][i], alone[2][i]};
    std::sort(c.begin(), c.end());
    max_difference = std::max(max_difference, std::abs(got[i] - 1.5 * (c[0] + c[1])));
    max_cost = std::max(max_cost, std::abs(static_cast<double>(c[0])));
    if (std::abs(got[i] - (c[0] + c[1] + c[2])) > 1e-3 * std::abs(c[2])) ++differs_from_sum;
  }
  EXPECT_GT(max_cost, 0.1);
  EXPECT_LT(max_difference, 1e-4 * max_cost);
  EXPECT_GT(differs_from_sum, got.size() / 2);  // the selection changed the data term
  EXPECT_LT(best.median_abs_error_m, 0.01);
  EXPECT_GT(best.completeness, 0.8);
  options.best_source_fraction = 0;
  ExpectRefusedNaming(options, "best_source_fraction");
  options.best_source_fraction = 1.5;
  ExpectRefusedNaming(options, "best_source_fraction");
}

// A rolled source: the reference's orientations must be carried into it, by the paper's epipole
// roll or by the plane homography (the default).
TEST(DepthEstimator, OrientationTransferIsNeededForARolledSource) {
  Surface plane;
  plane.point = {0, 0, 1};
  plane.normal = Eigen::Vector3d(0, 0, -1);
  const Eigen::Vector3d target(0, 0, 1);
  // A pair: the source rolled 60 degrees about its optical axis.
  const std::vector<StereoCamera> cameras = {LookAtCamera({0, 0, 0}, target, 100, 96, 72),
                                             LookAtCamera({0.3, 0.05, 0}, target, 100, 96, 72,
                                                          60.0 * M_PI / 180)};
  OrientationStereoOptions options = TestOptions();
  options.orientation_transfer = OrientationTransfer::kEpipoleRoll;
  const Result roll = Reconstruct(plane, cameras, 0.7, 1.5, options, 3);
  options.orientation_transfer = OrientationTransfer::kPlaneHomography;
  const Result homography = Reconstruct(plane, cameras, 0.7, 1.5, options, 3);
  options.orientation_transfer = OrientationTransfer::kNone;
  const Result without = Reconstruct(plane, cameras, 0.7, 1.5, options, 3);
  EXPECT_LT(roll.median_abs_error_m, 0.015);
  EXPECT_LT(homography.median_abs_error_m, 0.015);
  EXPECT_GT(without.median_abs_error_m, 3 * roll.median_abs_error_m);
  EXPECT_GT(without.median_abs_error_m, 3 * homography.median_abs_error_m);
  std::printf("roll 60 deg: median |error| %.4f m (epipole roll), %.4f m (plane homography), "
              "%.4f m without\n",
              roll.median_abs_error_m, homography.median_abs_error_m,
              without.median_abs_error_m);
}

// A source imaging the plane at s times the reference's scale meets the reference's level l
// at its level l + round(log2 s), clamped to the levels it has.
TEST(DepthEstimator, SourceLevelsFollowTheScaleAtWhichTheyImage) {
  const Eigen::Vector3d target(0, 0, 1);
  auto view = [&](double focal_px, int levels) {
    StereoViewData data;
    data.camera = LookAtCamera({0.1, 0, 0}, target, focal_px, 96, 72);
    data.orientation.assign(levels, FloatMap(1, 1, 2));
    return data;
  };
  const StereoViewData ref = view(100, 3);
  const std::vector<StereoViewData> others = {view(100, 3), view(130, 3), view(150, 3),
                                              view(200, 3), view(50, 3),  view(800, 3)};
  std::vector<const StereoViewData*> sources;
  for (const StereoViewData& v : others) sources.push_back(&v);
  const DepthLabels labels(0.9, 1.1, 16, true);
  std::vector<int> matched, level_for_level;
  for (const StereoViewData* source : sources) {
    const double ratio = SourceScaleRatio(ref, *source, labels);
    matched.push_back(SourceLevelOffset(ratio, true));
    level_for_level.push_back(SourceLevelOffset(ratio, false));
  }
  EXPECT_NEAR(SourceScaleRatio(ref, others[3], labels), 2.0, 1e-9);  // the same distance
  EXPECT_EQ(matched, std::vector<int>({0, 0, 1, 1, -1, 3}));
  EXPECT_EQ(level_for_level, std::vector<int>(6, 0));
  EXPECT_EQ(SourceLevelOffset(0, true), 0);  // the point behind the source
  // The best-matched level's mismatch over the 3 levels: none at twice or half the scale
  // matched, twice level for level; at 8 / 6 times the levels run out (the reference's level 0
  // meets the source's level 2 at 2 / 1.5 times); at a tenth every level meets the source's
  // level 0, 10, 5 and 2.5 times off, the best 2.5.
  EXPECT_DOUBLE_EQ(BestLevelScaleMismatch(others[3], 2.0, 1, false, 3), 1.0);
  EXPECT_DOUBLE_EQ(BestLevelScaleMismatch(others[3], 2.0, 0, false, 3), 2.0);
  EXPECT_DOUBLE_EQ(BestLevelScaleMismatch(others[4], 0.5, -1, false, 3), 1.0);
  EXPECT_DOUBLE_EQ(BestLevelScaleMismatch(others[4], 0.5, -1, false, 1), 2.0);
  EXPECT_DOUBLE_EQ(BestLevelScaleMismatch(others[5], 8.0, 3, false, 3), 2.0);
  EXPECT_DOUBLE_EQ(BestLevelScaleMismatch(others[5], 6.0, 3, false, 3), 1.5);
  const int tenth = SourceLevelOffset(0.1, true);
  EXPECT_EQ(tenth, -3);
  EXPECT_DOUBLE_EQ(BestLevelScaleMismatch(others[4], 0.1, tenth, false, 3), 2.5);
  EXPECT_EQ(BestLevelScaleMismatch(others[5], 0.0, 0, false, 3), 0.0);
  EXPECT_EQ(SourceLevel(others[3], 0, 1, false), 1);
  EXPECT_EQ(SourceLevel(others[3], 2, 1, false), 2);   // no level 3
  EXPECT_EQ(SourceLevel(others[4], 0, -1, false), 0);  // no level -1
  EXPECT_EQ(SourceLevel(others[4], 2, -1, false), 1);
  StereoViewData fewer_colours = view(200, 3);
  fewer_colours.rgb.assign(2, FloatMap(1, 1, 3));
  EXPECT_EQ(SourceLevel(fewer_colours, 1, 1, true), 1);  // the colour pyramid's last level
  EXPECT_EQ(SourceLevel(fewer_colours, 1, 1, false), 2);
}

// Sources imaging the plane at twice the reference's scale (twice its focal length and size)
// whose level 1 holds the field at the reference's scale and whose level 0 is noise: matched at
// their next coarser level (match_source_scale), the reference meets only the true fields and
// recovers the plane; level for level, its finest level meets the noise. (Rendered fields, with
// strands drawn in pixels and no filter bank, do not show the bands' mismatch itself: sources
// at twice the scale with a true level 0 score 1.3 mm matched, 1.0 mm level for level.)
TEST(DepthEstimator, SourcesAtTwiceTheScaleAreMatchedAtTheirNextCoarserLevel) {
  Surface plane;
  plane.point = {0, 0, 1};
  plane.normal = Eigen::Vector3d(std::sin(0.35), 0, -std::cos(0.35));
  const auto strands = MakeStrands(plane, 900, 0.6, 0.25, 1);
  const Eigen::Vector3d target(0, 0, 1);
  const testing_util::RenderedView ref =
      RenderView(LookAtCamera({0, 0, 0}, target, 100, 96, 72), plane, strands);
  std::vector<StereoViewData> views = {{ref.camera, Pyramid(ref.orientation, 3), {}, {}}};
  unsigned seed = 1;
  for (const Eigen::Vector3d& center :
       {Eigen::Vector3d(0.3, 0, 0), Eigen::Vector3d(-0.3, 0, 0), Eigen::Vector3d(0, -0.3, 0)}) {
    const StereoCamera big = LookAtCamera(center, target, 200, 192, 144);
    const std::vector<FloatMap> fine =
        Pyramid(RenderView(big.PyramidLevel(1), plane, strands).orientation, 2);
    const FloatMap noise = testing_util::RandomMap(192, 144, 2, seed++);
    views.push_back({big, {noise, fine[0], fine[1]}, {}, {}});
  }
  OrientationStereoOptions options = TestOptions();
  auto median_error = [&](const OrientationStereoOptions& o) {
    const Result result = EstimateAndCompare(views, ref.depth, 0.7, 1.5, o);
    EXPECT_GT(result.num_compared, ref.depth.NumPixels() / 2);
    return result.median_abs_error_m;
  };
  const double matched = median_error(options);
  options.match_source_scale = false;
  const double level_for_level = median_error(options);
  std::printf("sources at twice the scale: median |error| %.4f m matched, %.4f m level for "
              "level\n", matched, level_for_level);
  EXPECT_LT(matched, 0.01);
  EXPECT_GT(level_for_level, 3 * matched);
}

}  // namespace
}  // namespace hairmvs

namespace hairmvs {
namespace {

// Three non-zero pixels of squared magnitude 25, 1 and 4 (both channels) among zeros: 10.
TEST(MeanSquareOfNonZero, AveragesOnlyTheNonZeroPixels) {
  FloatMap field(3, 2, 2, 0.0f);
  field.At(0, 0, 0) = 3.0f;
  field.At(0, 0, 1) = -4.0f;
  field.At(1, 2, 1) = 1.0f;
  field.At(1, 1, 0) = -2.0f;
  EXPECT_DOUBLE_EQ(MeanSquareOfNonZero(field), 10.0);
  EXPECT_EQ(MeanSquareOfNonZero(FloatMap(3, 2, 2, 0.0f)), 0.0);
}

// The guide's scaling: the non-zero pixels' RMS magnitude becomes the target, directions and
// zeros stay; an all-zero field stays as it is.
TEST(ScaleToRms, NonZeroPixelsGetTheTargetRms) {
  FloatMap field(3, 2, 2, 0.0f);
  field.At(0, 0, 0) = 3;  // |O| = 5
  field.At(0, 0, 1) = 4;
  field.At(1, 2, 1) = -5;  // |O| = 5; four pixels stay 0
  const FloatMap scaled = ScaleToRms(field, 2.0);
  EXPECT_FLOAT_EQ(scaled.At(0, 0, 0), 1.2f);
  EXPECT_FLOAT_EQ(scaled.At(0, 0, 1), 1.6f);
  EXPECT_FLOAT_EQ(scaled.At(1, 2, 1), -2.0f);
  EXPECT_EQ(scaled.At(0, 1, 0), 0.0f);
  EXPECT_EQ(scaled.At(1, 1, 1), 0.0f);
  const FloatMap zeros(4, 4, 2, 0.0f);
  EXPECT_EQ(ScaleToRms(zeros, 1.0).Data(), zeros.Data());
}

// A 13 x 9 field of pseudo-random values in [-0.5, 0.5), every 7th pixel masked (zero).
FloatMap RandomOrientationField() {
  const int width = 13, height = 9;
  FloatMap field(width, height, 2);
  uint32_t state = 12345;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>(state >> 8) / 16777216.0f - 0.5f;
  };
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const bool masked = (r * width + c) % 7 == 0;
      field.At(r, c, 0) = masked ? 0.0f : next();
      field.At(r, c, 1) = masked ? 0.0f : next();
    }
  }
  return field;
}

// The local normalisation against explicit window sums: zero mean and unit variance (up to
// eps, relative_eps times the mean |O|^2 of the valid pixels) over each window of valid pixels;
// masked (zero) pixels stay zero.
TEST(NormalizeOrientationField, MatchesExplicitWindowStatistics) {
  const FloatMap field = RandomOrientationField();
  const int width = field.Width(), height = field.Height(), radius = 2;
  const float relative_eps = 0.5f;  // large, so that a wrong eps shows
  double num_valid = 0, total_sq = 0;
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const double re = field.At(r, c, 0), im = field.At(r, c, 1);
      if (re == 0.0 && im == 0.0) continue;
      num_valid += 1;
      total_sq += re * re + im * im;
    }
  }
  const double eps = relative_eps * total_sq / num_valid;
  const FloatMap normalized = NormalizeOrientationField(field, radius, relative_eps);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      if (field.At(r, c, 0) == 0.0f && field.At(r, c, 1) == 0.0f) {
        EXPECT_EQ(normalized.At(r, c, 0), 0.0f);
        EXPECT_EQ(normalized.At(r, c, 1), 0.0f);
        continue;
      }
      double n = 0, sre = 0, sim = 0, ssq = 0;
      for (int rr = std::max(0, r - radius); rr <= std::min(height - 1, r + radius); ++rr) {
        for (int cc = std::max(0, c - radius); cc <= std::min(width - 1, c + radius); ++cc) {
          const double re = field.At(rr, cc, 0), im = field.At(rr, cc, 1);
          if (re == 0.0 && im == 0.0) continue;
          n += 1;
          sre += re;
          sim += im;
          ssq += re * re + im * im;
        }
      }
      const double mre = sre / n, mim = sim / n;
      const double scale = 1.0 / std::sqrt(ssq / n - mre * mre - mim * mim + eps);
      EXPECT_NEAR(normalized.At(r, c, 0), (field.At(r, c, 0) - mre) * scale, 1e-4);
      EXPECT_NEAR(normalized.At(r, c, 1), (field.At(r, c, 1) - mim) * scale, 1e-4);
    }
  }
}

// eps scales with the field: a field with every confidence 100 times smaller (another
// confidence_gamma, or a darker photo) normalises to the same values.
TEST(NormalizeOrientationField, IndependentOfTheFieldsScale) {
  const FloatMap field = RandomOrientationField();
  FloatMap small = field;
  for (float& value : small.Data()) value *= 0.01f;
  const FloatMap expected = NormalizeOrientationField(field, 2, 0.1f);
  const FloatMap got = NormalizeOrientationField(small, 2, 0.1f);
  ASSERT_EQ(got.Data().size(), expected.Data().size());
  double max_difference = 0, max_value = 0;
  for (size_t i = 0; i < got.Data().size(); ++i) {
    max_difference = std::max(max_difference, std::abs(double(got.Data()[i]) - expected.Data()[i]));
    max_value = std::max(max_value, std::abs(double(expected.Data()[i])));
  }
  EXPECT_GT(max_value, 0.5);
  EXPECT_LT(max_difference, 1e-4 * max_value);
}

}  // namespace
}  // namespace hairmvs
