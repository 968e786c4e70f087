// Cost volumes of orientation-field stereo (Luo et al. 2012, Eq. 4-5) and of the photometric
// baseline, one launch per level and block of depth slices.
//
// Depth of slice k at pixel p (labels in "coarse label" units v):
//   v = label_base[p] + (slice_begin + k) * label_step,  t = depth_a + depth_b * v,
//   D = inverse_depth ? 1 / t : t.
// Projection into source view j (SfM pixel convention, at the level's resolution):
//   u = D * (Hj * (col + 0.5, row + 0.5, 1)) + bj, sample at (u.x / u.z - 0.5, u.y / u.z - 0.5).
// view_params, per view (16 floats): Hj (9, row-major), bj (3), cos(psi), sin(psi), homography,
// weight, with psi = 2 (phi_ref - phi_j) the epipole roll correction of Eq. 5 and weight view j's
// factor in the sum over the views (CostViewInput::weight). homography = 1: the
// reference orientation is instead carried into view j by the Jacobian, at the pixel, of the
// homography of the plane the strand lies in (TransferDirection in
// src/stereo/stereo_geometry.h): fronto-parallel, or, when has_gradient, tilted by
// log_depth_gradient (2 planes: the gradient of log depth per pixel).
// view_dims, per view (4 ints): width, height, offset of its planes in `source` (2 ints:
// hm_plane_offset).
// The reference orientation field is planar (Re plane, then Im plane); the source fields are
// interleaved (Re, Im per pixel), since they are sampled at scattered points.
// cost: [k][row][col] for k in [0, num_slices).

#include "common.clh"

inline float SampleDepth(float v, float depth_a, float depth_b, int inverse_depth) {
  const float t = depth_a + depth_b * v;
  return inverse_depth ? 1.0f / t : t;
}

// Bilinear sample of an interleaved 2-channel field (Re, Im per pixel) at pixel coordinates
// (x, y) (pixel centres at integers): a sample reads 2 to 4 cache lines rather than twice that
// from two planes. Returns 0 (and valid = 0) outside [0, w-1] x [0, h-1].
inline float2 Bilinear2(__global const float* field, int w, int h, float x, float y,
                        int* valid) {
  if (!(x >= 0.0f && y >= 0.0f && x <= (float)(w - 1) && y <= (float)(h - 1))) {
    *valid = 0;
    return (float2)(0.0f, 0.0f);
  }
  *valid = 1;
  int x0 = min((int)x, w - 2 < 0 ? 0 : w - 2);
  int y0 = min((int)y, h - 2 < 0 ? 0 : h - 2);
  const int x1 = min(x0 + 1, w - 1);
  const int y1 = min(y0 + 1, h - 1);
  const float fx = x - (float)x0;
  const float fy = y - (float)y0;
  const float2 v00 = vload2(y0 * w + x0, field), v01 = vload2(y0 * w + x1, field);
  const float2 v10 = vload2(y1 * w + x0, field), v11 = vload2(y1 * w + x1, field);
  const float w00 = (1.0f - fx) * (1.0f - fy), w01 = fx * (1.0f - fy);
  const float w10 = (1.0f - fx) * fy, w11 = fx * fy;
  float2 r;
  r.x = w00 * v00.x + w01 * v01.x + w10 * v10.x + w11 * v11.x;
  r.y = w00 * v00.y + w01 * v01.y + w10 * v10.y + w11 * v11.y;
  return r;
}

inline float Bilinear1(__global const float* plane, int w, int h, float x, float y) {
  int x0 = min((int)x, w - 2 < 0 ? 0 : w - 2);
  int y0 = min((int)y, h - 2 < 0 ? 0 : h - 2);
  const int x1 = min(x0 + 1, w - 1);
  const int y1 = min(y0 + 1, h - 1);
  const float fx = x - (float)x0;
  const float fy = y - (float)y0;
  return (1.0f - fx) * (1.0f - fy) * plane[y0 * w + x0] + fx * (1.0f - fy) * plane[y0 * w + x1] +
         (1.0f - fx) * fy * plane[y1 * w + x0] + fx * fy * plane[y1 * w + x1];
}

// SLICE_CHUNK (build option): slices per work-item of orientation_cost; what does not depend on
// the depth (the pixel's projection direction and carried strand direction in each view) is
// computed once for them.
#ifndef SLICE_CHUNK
#error "SLICE_CHUNK must be defined"
#endif

// Global size (width, height, ceil(num_slices / SLICE_CHUNK)).
__kernel void orientation_cost(__global const float* ref, int width, int height,
                               __global const float* source, __global const float* view_params,
                               __global const int* view_dims, int num_views,
                               __global const float* label_base, float label_step,
                               int slice_begin, int num_slices, float depth_a, float depth_b,
                               int inverse_depth, __global float* cost,
                               __global const float* log_depth_gradient, int has_gradient) {
  const int col = get_global_id(0);
  const int row = get_global_id(1);
  const int k0 = get_global_id(2) * SLICE_CHUNK;
  if (col >= width || row >= height) return;
  const int p = row * width + col;
  const int plane = width * height;
  const int count = min(SLICE_CHUNK, num_slices - k0);
  const float ore = ref[p];
  const float oim = ref[plane + p];
  float total[SLICE_CHUNK];
  for (int i = 0; i < count; ++i) total[i] = 0.0f;
  // r = |O_ref| > 0 (not only O_ref != 0: a denormal field's r underflows to 0, and ore / r
  // would be NaN).
  const float r = sqrt(ore * ore + oim * oim);
  if (r > 0.0f) {
    float depth[SLICE_CHUNK];
    for (int i = 0; i < count; ++i) {
      const float v = label_base[p] + (float)(slice_begin + k0 + i) * label_step;
      depth[i] = SampleDepth(v, depth_a, depth_b, inverse_depth);
    }
    const float gx = has_gradient ? log_depth_gradient[p] : 0.0f;
    const float gy = has_gradient ? log_depth_gradient[plane + p] : 0.0f;
    const float x = (float)col + 0.5f;
    const float y = (float)row + 0.5f;
    // O_ref = r exp(2i theta) and the strand direction (ct, st) = (cos theta, sin theta),
    // theta in (-90, 90] degrees. The half-angle formula is taken for the larger of the two only:
    // for the smaller, 1 -+ cos(2 theta) cancels in float (a strand 0.01 degrees off the axis
    // came out 40% off in sin theta), and sin(2 theta) = 2 st ct gives it instead.
    const float c2 = ore / r;
    float ct, st;
    if (c2 >= 0.0f) {
      ct = sqrt(0.5f * (1.0f + c2));
      st = oim / (2.0f * r * ct);
    } else {
      st = copysign(sqrt(0.5f * (1.0f - c2)), oim);
      ct = oim / (2.0f * r * st);
    }
    // The strand's plane tilts by the gradient g of log depth (plane_homography).
    const float kappa = gx * ct + gy * st;
    for (int j = 0; j < num_views; ++j) {
      __global const float* m = view_params + 16 * j;
      // The pixel's ray through H: the projection is u = D * (hpx, hpy, hpz) + b.
      const float hpx = m[0] * x + m[1] * y + m[2];
      const float hpy = m[3] * x + m[4] * y + m[5];
      const float hpz = m[6] * x + m[7] * y + m[8];
      // The strand direction H ((ct, st, 0) + kappa (x, y, 1)), before the Jacobian of the
      // division by u.z, which depends on the depth.
      const float hx = m[0] * ct + m[1] * st + kappa * hpx;
      const float hy = m[3] * ct + m[4] * st + kappa * hpy;
      const float hz = m[6] * ct + m[7] * st + kappa * hpz;
      const int w = view_dims[4 * j];
      const int h = view_dims[4 * j + 1];
      __global const float* src = source + hm_plane_offset(view_dims + 4 * j);
      for (int i = 0; i < count; ++i) {
        const float ux = depth[i] * hpx + m[9];
        const float uy = depth[i] * hpy + m[10];
        const float uz = depth[i] * hpz + m[11];
        if (uz <= 0.0f) continue;
        int valid;
        const float2 o = Bilinear2(src, w, h, ux / uz - 0.5f, uy / uz - 0.5f, &valid);
        if (!valid) continue;
        if (m[14] != 0.0f) {
          // The direction through the Jacobian (up to a positive factor) gives theta' and the
          // carried O' = r exp(2i theta').
          const float px = ux / uz, py = uy / uz;
          const float dx = hx - px * hz;
          const float dy = hy - py * hz;
          // A strand seen end-on in the source (its piece projects to a point) has no
          // direction there: no term, as in the CPU reference.
          if (!(dx * dx + dy * dy > 0.0f)) continue;
          const float scale = r / (dx * dx + dy * dy);
          total[i] -= m[15] * scale * ((dx * dx - dy * dy) * o.x + 2.0f * dx * dy * o.y);
        } else {
          // conj(O_ref) * O_v = (ore*o.x + oim*o.y) + i (ore*o.y - oim*o.x); times exp(i psi).
          const float re = ore * o.x + oim * o.y;
          const float im = ore * o.y - oim * o.x;
          total[i] -= m[15] * (re * m[12] - im * m[13]);
        }
      }
    }
  }
  for (int i = 0; i < count; ++i) cost[(size_t)(k0 + i) * plane + p] = total[i];
}

// Photometric baseline, step 1: for one source view, the warped colour and the products whose
// window means give the zero-mean NCC. Output planes per slice k (6 * num_slices planes):
//   [6k+0..2] warped R, G, B; [6k+3] sum_c Iv_c^2; [6k+4] sum_c Ir_c Iv_c; [6k+5] valid (0/1).
// ref_rgb, src_rgb: 3 planes each. m: this view's 16 view_params. Global (width, height, slices).
__kernel void photometric_warp(__global const float* ref_rgb, int width, int height,
                               __global const float* src_rgb, int src_width, int src_height,
                               __global const float* m, __global const float* label_base,
                               float label_step, int slice_begin, float depth_a, float depth_b,
                               int inverse_depth, __global float* out) {
  const int col = get_global_id(0);
  const int row = get_global_id(1);
  const int k = get_global_id(2);
  if (col >= width || row >= height) return;
  const int p = row * width + col;
  const size_t plane = (size_t)width * height;
  const float v = label_base[p] + (float)(slice_begin + k) * label_step;
  const float depth = SampleDepth(v, depth_a, depth_b, inverse_depth);
  const float x = (float)col + 0.5f;
  const float y = (float)row + 0.5f;
  const float ux = depth * (m[0] * x + m[1] * y + m[2]) + m[9];
  const float uy = depth * (m[3] * x + m[4] * y + m[5]) + m[10];
  const float uz = depth * (m[6] * x + m[7] * y + m[8]) + m[11];
  float c[3] = {0.0f, 0.0f, 0.0f};
  float valid = 0.0f;
  if (uz > 0.0f) {
    const float sx = ux / uz - 0.5f;
    const float sy = uy / uz - 0.5f;
    if (sx >= 0.0f && sy >= 0.0f && sx <= (float)(src_width - 1) &&
        sy <= (float)(src_height - 1)) {
      valid = 1.0f;
      const int sp = src_width * src_height;
      for (int ch = 0; ch < 3; ++ch) {
        c[ch] = Bilinear1(src_rgb + ch * sp, src_width, src_height, sx, sy);
      }
    }
  }
  __global float* o = out + (size_t)6 * k * plane + p;
  o[0] = c[0];
  o[plane] = c[1];
  o[2 * plane] = c[2];
  o[3 * plane] = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
  o[4 * plane] = ref_rgb[p] * c[0] + ref_rgb[plane + p] * c[1] + ref_rgb[2 * plane + p] * c[2];
  o[5 * plane] = valid;
}

// The least colour variance of an NCC window, as a fraction of its mean square colour (both
// summed over R, G, B), that has an NCC (PhotometricCostCpu's kMinNccVarianceRatio): colours
// that vary by about 1% of their level. Relative, since the float error of E[x^2] - E[x]^2 from
// the box filter's running sums grows with the colours' level, and dark hair has texture of a
// small variance too.
#define kMinNccVarianceRatio 1e-4f

// Photometric baseline, step 2: adds -NCC of one view to the cost block, from the window means
// of the warp planes (box-filtered photometric_warp output) and of the reference:
// ref_stats: [0..2] mean R, G, B; [3] mean sum_c Ir_c^2. Windows with any invalid sample add 0.
// Global (width, height, slices).
__kernel void photometric_accumulate(__global const float* ref_stats,
                                     __global const float* warp_means, int width, int height,
                                     __global float* cost) {
  const int col = get_global_id(0);
  const int row = get_global_id(1);
  const int k = get_global_id(2);
  if (col >= width || row >= height) return;
  const int p = row * width + col;
  const size_t plane = (size_t)width * height;
  __global const float* w = warp_means + (size_t)6 * k * plane + p;
  if (w[5 * plane] < 0.999f) return;
  const float square_r = ref_stats[3 * plane + p], square_v = w[3 * plane];
  float mean_rr = square_r, mean_vv = square_v;
  float cross = w[4 * plane];
  for (int ch = 0; ch < 3; ++ch) {
    const float mr = ref_stats[ch * plane + p];
    const float mv = w[ch * plane];
    cross -= mr * mv;
    mean_rr -= mr * mr;
    mean_vv -= mv * mv;
  }
  // A window without texture has no NCC: 0. Each variance on its own: in float, what E[x^2] -
  // E[x]^2 leaves of a flat window is rounding, which times a textured window's variance
  // passes any small bound on the product and makes an NCC of noise (up to 0.2 in the tests).
  const float ncc = mean_rr > kMinNccVarianceRatio * square_r &&
                            mean_vv > kMinNccVarianceRatio * square_v
                        ? cross / sqrt(mean_rr * mean_vv)
                        : 0.0f;
  cost[(size_t)k * plane + p] -= ncc;
}

// Adds `scale` times a block of slices at (src_width, src_height), bilinearly resampled to
// (width, height), into slices [slice_offset, slice_offset + num_slices) of `volume`
// [slice][row][col]. A pixel of the output is src_pixels_per_pixel source pixels wide and both
// grids start at the image origin (pyramid levels; SfM pixel centres).
// Global (width, height, num_slices).
__kernel void resample_accumulate(__global const float* src, int src_width, int src_height,
                                  __global float* volume, int width, int height,
                                  int slice_offset, float scale, float src_pixels_per_pixel) {
  const int col = get_global_id(0);
  const int row = get_global_id(1);
  const int k = get_global_id(2);
  if (col >= width || row >= height) return;
  const float sx = ((float)col + 0.5f) * src_pixels_per_pixel - 0.5f;
  const float sy = ((float)row + 0.5f) * src_pixels_per_pixel - 0.5f;
  const float x = clamp(sx, 0.0f, (float)(src_width - 1));
  const float y = clamp(sy, 0.0f, (float)(src_height - 1));
  const float value =
      Bilinear1(src + (size_t)k * src_width * src_height, src_width, src_height, x, y);
  volume[(size_t)(slice_offset + k) * width * height + row * width + col] += scale * value;
}

// best_source_fraction (src/stereo/cost_volume.h, SumBestSourcesCL): out[i] += count / num_best
// x the sum of the num_best lowest of volumes[(first + c) * size + i], c < count (ties to the
// lower c), summed in the order of c. One work-item per element; sources are few, so each
// value's rank is counted directly.
__kernel void sum_best_sources(__global const float* volumes, int first, int count,
                               int num_best, long size, float scale, __global float* out) {
  const long i = get_global_id(0);
  if (i >= size) return;
  __global const float* column = volumes + (long)first * size + i;
  float sum = 0.0f;
  for (int c = 0; c < count; ++c) {
    const float value = column[(long)c * size];
    int rank = 0;
    for (int m = 0; m < count; ++m) {
      const float other = column[(long)m * size];
      rank += (other < value || (other == value && m < c)) ? 1 : 0;
    }
    if (rank < num_best) sum += value;
  }
  out[i] += scale * sum;
}
