#include "src/orientation/orientation_field.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "src/core/logging.h"
#include "src/opencl/opencl_context.h"

namespace hairmvs {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;

// Absolute difference of two angles modulo 180 degrees, in [0, 90].
double AngleDiffDeg(double a_deg, double b_deg) {
  double d = std::fmod(std::abs(a_deg - b_deg), 180.0);
  return std::min(d, 180.0 - d);
}

double ThetaDeg(const FloatMap& field, int row, int col) {
  double t = 0.5 * std::atan2(field.At(row, col, 1), field.At(row, col, 0)) * kDegPerRad;
  return t < 0 ? t + 180 : t;
}

double Confidence(const FloatMap& field, int row, int col) {
  return std::hypot(field.At(row, col, 0), field.At(row, col, 1));
}

// Parallel lines along theta (from +x towards +y), `period_px` apart, Gaussian profile of
// std `width_px` across; pixel (col, row) is centred at (col + 0.5, row + 0.5).
// `across_out` receives the signed distance to the nearest line centre.
FloatMap Stripes(int w, int h, double theta_rad, double period_px, double width_px,
                 double background, double contrast, FloatMap* across_out = nullptr) {
  FloatMap image(w, h, 1);
  if (across_out != nullptr) *across_out = FloatMap(w, h, 1);
  const double c = std::cos(theta_rad), s = std::sin(theta_rad);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      // The centre is off the pixel grid so that no angle puts every line between pixels.
      const double x = col + 0.5 - w / 2.0 - 0.3, y = row + 0.5 - h / 2.0 - 0.2;
      const double across = -x * s + y * c;
      const double d = across - period_px * std::round(across / period_px);
      // Area-sampled (4 x 4 samples per pixel), as a camera integrates over its pixels.
      double value = 0;
      for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) {
          const double sub = d - (j - 1.5) / 4 * s + (i - 1.5) / 4 * c;
          const double e = sub - period_px * std::round(sub / period_px);
          value += std::exp(-0.5 * e * e / (width_px * width_px)) / 16;
        }
      }
      image.At(row, col) = static_cast<float>(background + contrast * value);
      if (across_out != nullptr) across_out->At(row, col) = static_cast<float>(d);
    }
  }
  return image;
}

// Concentric bright circles around the image centre, `period_px` apart.
FloatMap Rings(int w, int h, double period_px, double width_px, FloatMap* across_out) {
  FloatMap image(w, h, 1);
  *across_out = FloatMap(w, h, 1);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const double x = col + 0.5 - w / 2.0, y = row + 0.5 - h / 2.0;
      const double r = std::hypot(x, y);
      const double d = r - period_px * std::round(r / period_px);
      image.At(row, col) =
          static_cast<float>(0.2 + 0.6 * std::exp(-0.5 * d * d / (width_px * width_px)));
      across_out->At(row, col) = static_cast<float>(d);
    }
  }
  return image;
}

// A test image with structure at many angles and scales: noise, stripes, rings.
FloatMap MixedImage(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> noise(-0.05f, 0.05f);
  FloatMap across;
  const FloatMap rings = Rings(w, h, 5.0, 0.8, &across);
  const FloatMap stripes = Stripes(w, h, 0.3, 7.0, 0.7, 0.0, 0.5);
  FloatMap image(w, h, 1);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const float v = col < w / 2 ? rings.At(row, col) : stripes.At(row, col) + 0.2f;
      image.At(row, col) = std::clamp(v + noise(rng), 0.0f, 1.0f);
    }
  }
  return image;
}

class OrientationFieldTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { context_ = OpenCLContext::Create(); }
  static void TearDownTestSuite() { context_.reset(); }
  static std::shared_ptr<OpenCLContext> context_;
};
std::shared_ptr<OpenCLContext> OrientationFieldTest::context_;

// Compares one level of the kernel with the CPU reference: where the reference confidence is
// above a small threshold, the confidence agrees to 1e-3 (relative) and the angle exactly (the
// same of the filter bank's orientations, a degree apart), unless the two orientations are a
// tie in the reference's responses (|R| within 1e-5 relative).
struct Reference {
  FloatMap gray, mask, field;
  std::vector<FloatMap> responses;  // per filter
};

void ExpectMatchesReference(const Reference& ref, const FloatMap& kernel,
                            const OrientationFieldOptions& options, const std::string& what) {
  const FloatMap& gray = ref.gray;
  const FloatMap& mask = ref.mask;
  const FloatMap& reference = ref.field;
  const std::vector<FloatMap>& responses = ref.responses;
  ASSERT_EQ(kernel.Width(), reference.Width());
  ASSERT_EQ(kernel.Height(), reference.Height());
  ASSERT_EQ(kernel.Channels(), 2);
  int compared = 0, masked = 0, ties = 0, zeros = 0;
  double worst_relative = 0, worst_angle = 0;
  for (int row = 0; row < gray.Height(); ++row) {
    for (int col = 0; col < gray.Width(); ++col) {
      if (!mask.Empty() && mask.At(row, col) <= 0) {
        ++masked;
        ASSERT_EQ(kernel.At(row, col, 0), 0.0f) << what << " masked " << row << "," << col;
        ASSERT_EQ(kernel.At(row, col, 1), 0.0f) << what << " masked " << row << "," << col;
        continue;
      }
      const double f_ref = Confidence(reference, row, col);
      const double f_cl = Confidence(kernel, row, col);
      if (f_ref < 0.02) {
        // Too weak for the angle to be compared; the confidence still is, and where the
        // reference is 0 (the bright-strands rule's dark pixels) the kernel's is 0 too.
        ASSERT_NEAR(f_cl, f_ref, 2e-5) << what << " weak at " << row << "," << col;
        if (f_ref == 0) {
          ++zeros;
          ASSERT_EQ(f_cl, 0.0) << what << " zero at " << row << "," << col;
        }
        continue;
      }
      ++compared;
      ASSERT_NEAR(f_cl, f_ref, 1e-3 * f_ref) << what << " at " << row << "," << col;
      worst_relative = std::max(worst_relative, std::abs(f_cl - f_ref) / f_ref);
      const double diff = AngleDiffDeg(ThetaDeg(kernel, row, col), ThetaDeg(reference, row, col));
      if (diff > 1e-3) {
        ++ties;
        const int k_cl = static_cast<int>(std::lround(ThetaDeg(kernel, row, col))) % 180;
        const double best = std::pow(f_ref, 1.0 / options.confidence_gamma);
        EXPECT_GE(std::abs(responses[k_cl].At(row, col)), best * (1 - 1e-5))
            << what << ": angle " << ThetaDeg(kernel, row, col) << " vs "
            << ThetaDeg(reference, row, col) << " at " << row << "," << col;
      } else {
        worst_angle = std::max(worst_angle, diff);
      }
    }
  }
  std::printf("%s: %d pixels compared, confidence rel. error <= %.2e, angle error <= %.3f deg, "
              "%d tie(s), %d zero(s)\n", what.c_str(), compared, worst_relative, worst_angle, ties,
              zeros);
  // The bright-strands rule zeroes the pixels of dark strands, which MixedImage has.
  if (!options.dark_strands) {
    EXPECT_GT(zeros, 0) << what;
  }
  EXPECT_GT(compared, static_cast<int>(gray.NumPixels() / 4)) << what;
  if (!mask.Empty()) {
    EXPECT_GT(masked, 0) << what;
  }
}

TEST_F(OrientationFieldTest, KernelMatchesCpuReferenceAtEveryLevel) {
  // An odd size: row tails shorter than a vector, odd sizes at every level.
  const FloatMap gray = MixedImage(83, 61, 7);
  // A mask with a hole, whose bounding box is the whole image, and an ellipse whose box
  // reaches the image's right and bottom edges but not its left and top ones (the kernel
  // filters only the box, with the image's pixels around it as inputs).
  FloatMap holed(gray.Width(), gray.Height(), 1, 1.0f);
  FloatMap ellipse(gray.Width(), gray.Height(), 1, 0.0f);
  for (int row = 0; row < gray.Height(); ++row) {
    for (int col = 0; col < gray.Width(); ++col) {
      if (std::hypot(col - 60, row - 20) < 9) holed.At(row, col) = 0;
      if (std::hypot((col - 49) / 34.0, (row - 34) / 27.0) < 1) ellipse.At(row, col) = 1;
    }
  }
  ASSERT_EQ(ellipse.At(34, gray.Width() - 1), 1.0f);
  ASSERT_EQ(ellipse.At(gray.Height() - 1, 49), 1.0f);
  ASSERT_EQ(ellipse.At(34, 0), 0.0f);
  ASSERT_EQ(ellipse.At(0, 49), 0.0f);
  for (const auto& [mask_name, mask] : {std::pair<std::string, FloatMap>{"holed mask", holed},
                                        std::pair<std::string, FloatMap>{"ellipse", ellipse}}) {
    // Dark strands counted (the default) and bright strands only (the paper's rule).
    for (bool dark_strands : {true, false}) {
      OrientationFieldOptions options;
      options.dark_strands = dark_strands;
      const OrientationFilterBank bank(options);
      std::vector<Reference> references(3);
      for (int l = 0; l < 3; ++l) {
        Reference& ref = references[l];
        ref.gray = l == 0 ? gray : DownsampleHalf(references[l - 1].gray);
        ref.mask = l == 0 ? mask : DownsampleMask(references[l - 1].mask);
        ref.field = ComputeOrientationLevelReference(ref.gray, ref.mask, bank,
                                                     options.confidence_gamma,
                                                     options.SignedResponseRatio(), &ref.responses);
      }
      // The default configuration, and one with 16-pixel vectors, a block size that leaves a
      // partial last block (180 = 25 * 7 + 5) and other work-group sizes.
      for (const OrientationKernelConfig& config :
           {OrientationKernelConfig(), OrientationKernelConfig{16, 7, 2, 2}}) {
        OrientationFieldComputer computer(context_, options, config);
        const std::vector<FloatMap> levels = computer.Compute(gray, mask);
        ASSERT_EQ(levels.size(), 3u);
        for (int l = 0; l < 3; ++l) {
          ExpectMatchesReference(references[l], levels[l], options,
                                 mask_name + ", " +
                                     (dark_strands ? "dark strands too" : "bright only") +
                                     ", level " + std::to_string(l) + " vec " +
                                     std::to_string(config.vector_width) + " block " +
                                     std::to_string(config.block_size));
        }
      }
    }
  }
}

TEST_F(OrientationFieldTest, LevelSizesAndDownsampling) {
  FloatMap gray(7, 5, 1);
  for (int row = 0; row < 5; ++row) {
    for (int col = 0; col < 7; ++col) gray.At(row, col) = static_cast<float>(row * 7 + col);
  }
  const FloatMap half = DownsampleHalf(gray);
  ASSERT_EQ(half.Width(), 4);
  ASSERT_EQ(half.Height(), 3);
  EXPECT_FLOAT_EQ(half.At(0, 0), (0 + 1 + 7 + 8) / 4.0f);
  EXPECT_FLOAT_EQ(half.At(0, 3), (6 + 13) / 2.0f);      // odd last column
  EXPECT_FLOAT_EQ(half.At(2, 3), 34.0f);                 // odd corner
  FloatMap mask(7, 5, 1, 1.0f);
  mask.At(0, 0) = mask.At(0, 1) = mask.At(1, 0) = 0;  // 3 of 4 excluded -> excluded
  mask.At(2, 2) = 0;                                    // 1 of 4 excluded -> kept
  const FloatMap half_mask = DownsampleMask(mask);
  EXPECT_EQ(half_mask.At(0, 0), 0.0f);
  EXPECT_EQ(half_mask.At(1, 1), 1.0f);
  OrientationFieldComputer computer(context_, OrientationFieldOptions());
  const auto levels = computer.Compute(MixedImage(37, 26, 3), FloatMap());
  ASSERT_EQ(levels.size(), 3u);
  EXPECT_EQ(levels[1].Width(), 19);
  EXPECT_EQ(levels[1].Height(), 13);
  EXPECT_EQ(levels[2].Width(), 10);
  EXPECT_EQ(levels[2].Height(), 7);
}

// Bright thin lines at each of the 180 filter angles: the angle is recovered within 1 degree
// at every pixel within 0.5 px of a line centre (away from the image border). Half a degree
// off the filter angles the error stays within 1.5 degrees: one filter step of bias towards
// the nearer image axis remains within ~5 degrees of the axes (the 0.5 px inner Gaussian
// is finer than the pixel grid; see OrientationFieldOptions::filter_supersampling).
TEST_F(OrientationFieldTest, StripesAtEveryAngle) {
  OrientationFieldComputer computer(context_, OrientationFieldOptions());
  const int w = 48, h = 48;
  double worst_on_filter_angles = 0, worst_between = 0;
  for (int half_steps = 0; half_steps < 360; ++half_steps) {
    const double theta_deg = 0.5 * half_steps;
    const bool filter_angle = half_steps % 2 == 0;
    FloatMap across;
    const FloatMap gray = Stripes(w, h, theta_deg / kDegPerRad, 7.0, 0.7, 0.2, 0.6, &across);
    const FloatMap field = computer.ComputeLevel(gray, FloatMap());
    int checked = 0;
    for (int row = 16; row < 32; ++row) {
      for (int col = 16; col < 32; ++col) {
        if (std::abs(across.At(row, col)) > 0.5) continue;
        ++checked;
        ASSERT_GT(Confidence(field, row, col), 0.2) << theta_deg << " deg at " << row << "," << col;
        const double diff = AngleDiffDeg(ThetaDeg(field, row, col), theta_deg);
        // 1e-3: the float round trip through cos/sin/atan2 of the output.
        ASSERT_LE(diff, (filter_angle ? 1.0 : 1.5) + 1e-3)
            << theta_deg << " deg at " << row << "," << col;
        double& worst = filter_angle ? worst_on_filter_angles : worst_between;
        worst = std::max(worst, diff);
      }
    }
    ASSERT_GE(checked, 16) << theta_deg;
  }
  std::printf("stripes: worst angle error %.3f deg on the filter angles, %.3f between them\n",
              worst_on_filter_angles, worst_between);
}

// Concentric bright circles: the orientation is tangential (perpendicular to the radius).
TEST_F(OrientationFieldTest, RingsAreTangential) {
  OrientationFieldComputer computer(context_, OrientationFieldOptions());
  const int w = 120, h = 120;
  FloatMap across;
  const FloatMap gray = Rings(w, h, 6.0, 0.7, &across);
  const FloatMap field = computer.ComputeLevel(gray, FloatMap());
  std::vector<double> errors;
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const double x = col + 0.5 - w / 2.0, y = row + 0.5 - h / 2.0;
      const double r = std::hypot(x, y);
      // Within 0.25 px of a ring centre. Further out, the curvature biases the angle: a pixel
      // 0.4 px outside a ring of radius 30 gets up to 8 degrees, as one arm of a tilted filter
      // then follows the ring (measured; a property of the filter, not of its discretisation).
      if (r < 20 || r > 45 || std::abs(across.At(row, col)) > 0.25) continue;
      const double tangent_deg = std::atan2(y, x) * kDegPerRad + 90.0;
      errors.push_back(AngleDiffDeg(ThetaDeg(field, row, col), tangent_deg));
    }
  }
  ASSERT_GT(errors.size(), 300u);
  std::sort(errors.begin(), errors.end());
  const double median = errors[errors.size() / 2], worst = errors.back();
  std::printf("rings: %zu pixels, median error %.3f deg, worst %.3f deg\n", errors.size(), median,
              worst);
  EXPECT_LE(median, 0.5);
  EXPECT_LE(worst, 1.5);
}

// Dark strands on a bright background respond negatively at their own angle. With the paper's
// rule (bright strands only) O = 0 on them; with dark_strands (the default) their field is that
// of their bright twin, the image 1 - I, on its strands: the zero-sum filters respond to it
// with the opposite sign and the same magnitude. (Between the strands every angle responds
// weakly and alike, and the two images' rounding may pick different angles there.)
TEST_F(OrientationFieldTest, DarkStrandsGiveZeroOrTheirBrightTwinsField) {
  OrientationFieldOptions bright_only;
  bright_only.dark_strands = false;
  OrientationFieldComputer paper(context_, bright_only);
  OrientationFieldComputer computer(context_, OrientationFieldOptions());
  int checked = 0;
  for (double theta_deg : {0.0, 17.0, 45.0, 90.0, 133.5}) {
    FloatMap across;
    const FloatMap gray = Stripes(64, 64, theta_deg / kDegPerRad, 9.0, 0.7, 0.8, -0.6, &across);
    const FloatMap bright = Stripes(64, 64, theta_deg / kDegPerRad, 9.0, 0.7, 0.2, 0.6);
    const FloatMap field = paper.ComputeLevel(gray, FloatMap());
    const FloatMap bright_field = paper.ComputeLevel(bright, FloatMap());
    const FloatMap dark_field = computer.ComputeLevel(gray, FloatMap());
    for (int row = 16; row < 48; ++row) {
      for (int col = 16; col < 48; ++col) {
        if (std::abs(across.At(row, col)) > 0.3) continue;
        ++checked;
        EXPECT_EQ(field.At(row, col, 0), 0.0f) << theta_deg << " at " << row << "," << col;
        EXPECT_EQ(field.At(row, col, 1), 0.0f) << theta_deg << " at " << row << "," << col;
        EXPECT_GT(Confidence(bright_field, row, col), 0.3);  // the bright twin responds
        for (int ch = 0; ch < 2; ++ch) {  // and so does the dark strand, alike
          EXPECT_NEAR(dark_field.At(row, col, ch), bright_field.At(row, col, ch), 1e-4)
              << theta_deg << " at " << row << "," << col;
        }
      }
    }
  }
  EXPECT_GT(checked, 50);
}

// Masked pixels are 0 at every level, whatever the image; the others are not.
TEST_F(OrientationFieldTest, MaskedPixelsAreZeroAtEveryLevel) {
  OrientationFieldComputer computer(context_, OrientationFieldOptions());
  const FloatMap gray = Stripes(70, 50, 0.7, 5.0, 0.7, 0.2, 0.6);
  FloatMap mask(70, 50, 1, 1.0f);
  for (int row = 0; row < 50; ++row) {
    for (int col = 0; col < 35; ++col) mask.At(row, col) = 0;
  }
  const auto levels = computer.Compute(gray, mask);
  FloatMap level_mask = mask;
  for (size_t l = 0; l < levels.size(); ++l) {
    if (l > 0) level_mask = DownsampleMask(level_mask);
    int valid_nonzero = 0;
    for (int row = 0; row < level_mask.Height(); ++row) {
      for (int col = 0; col < level_mask.Width(); ++col) {
        if (level_mask.At(row, col) == 0) {
          ASSERT_EQ(levels[l].At(row, col, 0), 0.0f) << "level " << l;
          ASSERT_EQ(levels[l].At(row, col, 1), 0.0f) << "level " << l;
        } else if (Confidence(levels[l], row, col) > 0) {
          ++valid_nonzero;
        }
      }
    }
    EXPECT_GT(valid_nonzero, static_cast<int>(level_mask.NumPixels() / 8)) << "level " << l;
  }
  EXPECT_THROW(computer.Compute(gray, FloatMap(10, 10, 1)), Error);
  // A view with no hair at all: every level 0, no error.
  for (const FloatMap& level : computer.Compute(gray, FloatMap(70, 50, 1, 0.0f))) {
    for (float v : level.Data()) ASSERT_EQ(v, 0.0f);
  }
}

}  // namespace
}  // namespace hairmvs
