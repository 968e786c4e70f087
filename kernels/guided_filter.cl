// Structure-aware aggregation (Luo et al. 2012, Eq. 7-8): a guided filter (He et al.) with the
// reference orientation field O = (Re O, Im O) as a 2-channel guide with isotropic variance:
//   a_k = (mean_k(O c) - mu_k mean_k(c)) / (sigma_k^2 + eps),  b_k = mean_k(c) - a_k . mu_k,
//   q_p = mean_{k in w_p}(a_k) . O_p + mean_{k in w_p}(b_k),
// with sigma_k^2 = mean_k(|O|^2) - |mu_k|^2. This equals q_p = sum_p' W(p, p') c_p' of Eq. 8.
// Window means use running sums (O(1) per pixel whatever the radius); windows are clipped at
// the image border and normalised by the number of pixels inside.
// All buffers are planar: plane i of a w x h map starts at i * w * h.

// Horizontal window sums of `num_planes` planes, one work-item per (row, plane).
// Global (height, num_planes). Output: sum over [col - r, col + r] clipped, divided by count.
__kernel void box_rows(__global const float* in, __global float* out, int width, int height,
                       int radius) {
  const int row = get_global_id(0);
  const int plane = get_global_id(1);
  if (row >= height) return;
  const size_t base = (size_t)plane * width * height + (size_t)row * width;
  __global const float* src = in + base;
  __global float* dst = out + base;
  float sum = 0.0f;
  const int first = min(radius, width - 1);
  for (int c = 0; c <= first; ++c) sum += src[c];
  for (int c = 0; c < width; ++c) {
    const int lo = max(c - radius, 0);
    const int hi = min(c + radius, width - 1);
    dst[c] = sum / (float)(hi - lo + 1);
    const int add = c + radius + 1;
    const int remove = c - radius;
    if (add < width) sum += src[add];
    if (remove >= 0) sum -= src[remove];
  }
}

// Vertical window means, one work-item per 8 neighbouring columns of a plane: it reads and
// writes 8 neighbouring floats per row, which on a CPU device (PoCL runs a work-item's loop to
// its end before the next work-item) is a third of the cache lines that one column per
// work-item touches. The same arithmetic per column as one column per work-item.
// Global (ceil(width / 8), num_planes).
__kernel void box_cols(__global const float* in, __global float* out, int width, int height,
                       int radius) {
  const int col0 = 8 * get_global_id(0);
  const int plane = get_global_id(1);
  if (col0 >= width) return;
  const size_t base = (size_t)plane * width * height + col0;
  __global const float* src = in + base;
  __global float* dst = out + base;
  const int first = min(radius, height - 1);
  if (col0 + 8 <= width) {
    float8 sum = (float8)(0.0f);
    for (int r = 0; r <= first; ++r) sum += vload8(0, src + (size_t)r * width);
    for (int r = 0; r < height; ++r) {
      const int lo = max(r - radius, 0);
      const int hi = min(r + radius, height - 1);
      vstore8(sum / (float8)((float)(hi - lo + 1)), 0, dst + (size_t)r * width);
      const int add = r + radius + 1;
      const int remove = r - radius;
      if (add < height) sum += vload8(0, src + (size_t)add * width);
      if (remove >= 0) sum -= vload8(0, src + (size_t)remove * width);
    }
    return;
  }
  for (int c = 0; c < width - col0; ++c) {  // the last, partial group
    float sum = 0.0f;
    for (int r = 0; r <= first; ++r) sum += src[(size_t)r * width + c];
    for (int r = 0; r < height; ++r) {
      const int lo = max(r - radius, 0);
      const int hi = min(r + radius, height - 1);
      dst[(size_t)r * width + c] = sum / (float)(hi - lo + 1);
      const int add = r + radius + 1;
      const int remove = r - radius;
      if (add < height) sum += src[(size_t)add * width + c];
      if (remove >= 0) sum -= src[(size_t)remove * width + c];
    }
  }
}

// Guide planes for box filtering: [0] Re O, [1] Im O, [2] |O|^2. Global (width * height).
__kernel void gf_guide_planes(__global const float* guide, __global float* out, int num_pixels) {
  const int p = get_global_id(0);
  if (p >= num_pixels) return;
  const float g0 = guide[p];
  const float g1 = guide[num_pixels + p];
  out[p] = g0;
  out[num_pixels + p] = g1;
  out[2 * num_pixels + p] = g0 * g0 + g1 * g1;
}

// In place: window means [mu0, mu1, mean |O|^2] -> [mu0, mu1, 1 / (sigma^2 + eps)].
__kernel void gf_guide_stats(__global float* stats, int num_pixels, float eps) {
  const int p = get_global_id(0);
  if (p >= num_pixels) return;
  const float m0 = stats[p];
  const float m1 = stats[num_pixels + p];
  const float var = max(stats[2 * num_pixels + p] - m0 * m0 - m1 * m1, 0.0f);
  stats[2 * num_pixels + p] = 1.0f / (var + eps);
}

// Products to box-filter, per slice k: [3k] c, [3k+1] O0 c, [3k+2] O1 c.
// Global (width * height, num_slices).
__kernel void gf_products(__global const float* cost, __global const float* guide,
                          __global float* out, int num_pixels) {
  const int p = get_global_id(0);
  const int k = get_global_id(1);
  if (p >= num_pixels) return;
  const float c = cost[(size_t)k * num_pixels + p];
  __global float* o = out + (size_t)3 * k * num_pixels + p;
  o[0] = c;
  o[num_pixels] = guide[p] * c;
  o[2 * num_pixels] = guide[num_pixels + p] * c;
}

// In place, per slice: window means [mean c, mean O0 c, mean O1 c] -> [a0, a1, b].
__kernel void gf_coefficients(__global float* planes, __global const float* stats,
                              int num_pixels) {
  const int p = get_global_id(0);
  const int k = get_global_id(1);
  if (p >= num_pixels) return;
  __global float* o = planes + (size_t)3 * k * num_pixels + p;
  const float mc = o[0];
  const float mu0 = stats[p];
  const float mu1 = stats[num_pixels + p];
  const float inv = stats[2 * num_pixels + p];
  const float a0 = (o[num_pixels] - mu0 * mc) * inv;
  const float a1 = (o[2 * num_pixels] - mu1 * mc) * inv;
  o[0] = a0;
  o[num_pixels] = a1;
  o[2 * num_pixels] = mc - a0 * mu0 - a1 * mu1;
}

// Output per slice: q = mean(a0) O0 + mean(a1) O1 + mean(b).
__kernel void gf_output(__global const float* planes, __global const float* guide,
                        __global float* out, int num_pixels) {
  const int p = get_global_id(0);
  const int k = get_global_id(1);
  if (p >= num_pixels) return;
  __global const float* o = planes + (size_t)3 * k * num_pixels + p;
  out[(size_t)k * num_pixels + p] =
      o[0] * guide[p] + o[num_pixels] * guide[num_pixels + p] + o[2 * num_pixels];
}
