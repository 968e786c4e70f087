#pragma once
// Orientation fields (Luo et al. 2012, Section 2; method.md section 1): for every pixel the
// strand direction Theta (modulo pi, measured from image +x towards +y, i.e. clockwise on
// screen) and a confidence F, stored as O = F exp(2 i Theta) so that opposite directions agree.
// Three levels: the image, then 2x2 box-downsampled copies, filtered with the same filters.

#include <string>
#include <vector>

#include "src/core/timer.h"

namespace hairmvs {

struct OrientationFieldOptions {
  // Paper: 3 levels (full, 1/2, 1/4 resolution); at most kMaxLevels.
  int num_levels = 3;
  static constexpr int kMaxLevels = 8;
  // Paper: 180 filters, 1 degree apart, theta in [0, pi).
  int num_orientations = 180;
  // K0(x, y) = (G_inner(x) - G_outer(x)) G_along(y): a ridge detector, narrow positive centre
  // minus a wider surround across the strand, elongated along it (paper Section 2).
  // Across: 1 / 2 px, twice the paper's 0.5 / 1 px. In photos of a head at about 1 Mpixel a
  // strand is under a pixel wide and the narrow filter responds mostly to image noise (24- and
  // 64-sample renders); the wider one follows strand bundles, which the views share. Measured
  // (orientation_stereo, .geometric maps, paper's -> this): synth_handheld, 20 views: per-pixel
  // median 38.19 -> 8.62 mm, 51.4 -> 58.7% of the hair, 3D median 1.81 -> 0.88 mm;
  // synth_straight_gantry, 32 views: median 4.64 -> 4.73 mm, 95.2 -> 97.4% of the hair, 3D mean
  // 1.84 -> 1.43 mm (median 0.579 -> 0.575); the demo's synthesised curly group: median 2.36 ->
  // 2.39 mm, mean 3.71 -> 3.59 mm; a synthesised straight group at 1404 x 936: median 6.10 ->
  // 5.32 mm. The filter bank takes about 1.6x as long (4 views at 1404 x 936: 3.2 -> 5.2 s of
  // 64-69 s). Along: the paper's 4 px (8 px: handheld 9.97 mm, curly 2.61).
  // Measured again on the final pipeline (603a8b0, `bash scripts/evaluate_stereo.sh SET OUT
  // --OrientationField.sigma_across_inner_px 0.5 ...`, .geometric, per-pixel median), this ->
  // the paper's 0.5 / 1 / 4 -> 0.5 / 1 / 8: synth_straight_gantry 4.32 -> 4.34 -> 4.29 mm,
  // synth_handheld 5.41 -> 5.91 -> 6.07 mm (3D median 0.637 -> 0.785 -> 0.816 mm). The narrow
  // filters win on the single view g2_c alone (4.02 -> 3.79 -> 3.72 mm) but not on the sets.
  double sigma_across_inner_px = 1.0;
  double sigma_across_outer_px = 2.0;
  double sigma_along_px = 4.0;
  // F = (max_theta |K_theta * I|)^gamma: how much a strong strand outweighs a faint one (a
  // shadowed strand further in) in the matching. Measured on ebc0fb2 (the g2 group of
  // synth_straight_gantry, `bash scripts/evaluate_stereo.sh ../shared/data/synth_straight_gantry
  // OUT --image_names g2_b.png,g2_c.png,g2_l.png,g2_r.png --OrientationField.confidence_gamma
  // G`; complete / per-pixel mean / median): 0.25 98.3% / 6.35 / 4.14 mm, 0.5 99.6% / 6.07 /
  // 4.02, 1 99.7% / 6.27 / 4.09 mm; the depths' `layer` 33 / 31 / 33%.
  double confidence_gamma = 0.5;
  // The filter's support: the rectangle |along| <= t sigma_along, |across| <= t sigma_outer
  // (rotated with the filter); beyond 3 sigma the Gaussians are below 1.1% of their peak.
  double truncation_sigmas = 3.0;
  // Each tap's weight is the integral of the continuous filter over the part of the tap's
  // pixel square inside the support, from n x n samples. n = 1 is plain point sampling,
  // which aliases the 0.5 px inner Gaussian: the axis-aligned filters come out sharper than
  // the oblique ones and lines within ~5 degrees of the image axes snap to the axis (measured
  // on synthetic stripes: up to 5.5 degrees error with n = 1, <= 1.5 with n = 8).
  int filter_supersampling = 8;
  // 1: scale the outer (negative) part so that every filter sums to exactly zero, as the
  // continuous one does: flat regions then respond 0 at every angle. 0: the plain integrals
  // (the truncated outer Gaussian has 0.27% less mass: flat bright regions respond weakly).
  bool normalize_sampled_filters = true;
  // O = 0 unless max_theta (K_theta * I) > this fraction of max_theta |K_theta * I|. The paper
  // (Eq. 1) says > 0, but on a dark strand the filters across it respond ~0 with a rounding-
  // and sampling-level sign (measured: 1e-5 of the strand's |response|), which would let a
  // dark strand through at random; 1e-4 treats such responses as zero. 0 = the paper's test.
  double min_positive_response_ratio = 1e-4;
  // Dark strands make the field too: O from the largest |response| whatever its sign, where the
  // paper (Eq. 1) keeps only bright strands (false: O = 0 unless the largest signed response
  // passes the test above). Dark hair seen against something brighter (the skin through a thin
  // fringe, lit strands further in) is a dark ridge: the paper's rule drops it and keeps the
  // bright gaps beside it, which run at the strands' angle but lie at the depth of what is
  // seen through them. Measured (orientation_stereo, .geometric maps; complete / per-pixel
  // mean / median / 3D mean / 3D median, mm; paper's rule -> dark strands too): synth_handheld
  // (in its true cameras) 92.0% / 10.53 / 5.14 / 1.711 / 0.618 -> 93.3% / 9.91 / 4.78 / 1.304 /
  // 0.588, its face-side views h10-h13 most (h11 18.1 -> 11.0 mm, h12 8.5 -> 6.3); data term
  // alone 14.80 -> 11.00 mm; synth_straight_gantry 98.6% / 8.08 / 4.32 / 1.210 / 0.558 -> 98.6%
  // / 8.09 / 4.24 / 1.122 / 0.526, data term 4.90 -> 4.77 mm; the demo's curly T group (hairmvs's
  // own renders, whose gaps are dark) 98.4% / 3.47 / 2.38 / 0.301 / 0.243 -> 97.8% / 3.70 / 2.45
  // / 0.289 / 0.229, at 1404 x 936 2.27 -> 2.28 mm; its straight renders (8 T groups) 97.6% /
  // 5.92 / 2.66 / 0.752 / 0.351 -> 96.4% / 6.96 / 2.77 / 0.770 / 0.322, worse near the
  // silhouettes (5.57 -> 6.73 mm). Signing the field by polarity instead (a
  // dark strand's O negated, so that it matches only dark strands) was worse: synth_handheld
  // 7.88 mm, the curly group 2.45.
  bool dark_strands = true;

  template <typename Visitor>
  void ForEachField(Visitor&& v) {
    v("num_levels", &num_levels, "number of pyramid levels (2x2 box downsampling)");
    v("num_orientations", &num_orientations, "number of filter angles in [0, pi)");
    v("sigma_across_inner_px", &sigma_across_inner_px,
      "inner (positive) Gaussian across the strand");
    v("sigma_across_outer_px", &sigma_across_outer_px,
      "outer (negative) Gaussian across the strand");
    v("sigma_along_px", &sigma_along_px, "Gaussian along the strand");
    v("confidence_gamma", &confidence_gamma, "F = (max |response|)^gamma");
    v("truncation_sigmas", &truncation_sigmas,
      "filter support: |along| <= t*sigma_along, |across| <= t*sigma_outer");
    v("normalize_sampled_filters", &normalize_sampled_filters,
      "scale the outer Gaussian part so that every filter sums to zero");
    v("min_positive_response_ratio", &min_positive_response_ratio,
      "bright-strand test: max signed response > ratio * max |response| (paper: 0)");
    v("dark_strands", &dark_strands,
      "dark strands make the field too (0: only bright ones, as the paper's Eq. 1)");
    v("filter_supersampling", &filter_supersampling,
      "n x n samples per tap averaged over its pixel (1 = point sampling)");
  }
  bool Check(std::string* error) const;
  // r of the field's test, max signed response > r max |response|: min_positive_response_ratio
  // for bright strands only, -1 (every pixel with a response) with dark_strands.
  double SignedResponseRatio() const { return dark_strands ? -1.0 : min_positive_response_ratio; }
};

// What `hairmvs orientation_fields` does, for a workspace.
struct OrientationFieldsRunOptions {
  // Empty: every image of the workspace.
  std::vector<std::string> image_names;
  // Also write <name>.l<k>.png: hue = strand angle, brightness = confidence (per image).
  bool write_png = false;
  // Masks folder (see Workspace::Read); empty = <workspace>/masks if it exists.
  std::string mask_path;
  // --OpenCL.device (see src/opencl/opencl_options.h).
  std::string opencl_device;
  // > 0: the images area-resized so that their larger side is at most this, as the stereo
  // reads them with the same --OrientationStereo.max_image_size (which then reuses the fields
  // written); -1: full size.
  int max_image_size = -1;
  // An image whose fields in stereo/orientation_maps/ are up to date (their provenance holds:
  // the same image and mask bytes, size and filter options; with write_png, its pictures
  // there) is not computed again, as colmap feature_extractor skips the images it has
  // features of. false: every image is computed again.
  bool skip_up_to_date = true;
};

struct OrientationFieldsResult {
  int num_images = 0;  // computed
  int num_up_to_date = 0;  // skipped: up to date (skip_up_to_date)
  int num_levels = 0;
  int num_files_written = 0;
  double seconds = 0;
  std::string device_name;
  std::string BriefReport() const;
};

// Writes W/stereo/orientation_maps/<image name>.l<k>.bin (2-channel Mat: Re O, Im O) for
// every level k, and <image name>.provenance.txt: what they were computed from, so that the
// stereo reuses them only while that holds (src/orientation/orientation_maps.h). Adds the
// per-stage times to `timings` (may be null).
OrientationFieldsResult RunOrientationFields(const std::string& workspace_path,
                                             const OrientationFieldOptions& options,
                                             const OrientationFieldsRunOptions& run_options,
                                             StageTimings* timings);

}  // namespace hairmvs
