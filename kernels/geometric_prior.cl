// The geometric pass's prior (src/stereo/geometric_prior.h): for pixel p of the reference's grid
// and label v = (has_base ? label_base[p] : 0) + k * label_step, at depth D(v), where
// (has_active ? active[p] : 1) is non-zero,
//   volume[k][p] += per_view_weight * sum_j min(e_j, max_error_px) / max_error_px,
// e_j COLMAP's forward-backward reprojection error through view j's depth map (in level-0
// pixels: the grid's error times level0_px_per_grid_px), max_error_px where view j does not see
// the point or has no depth there.
// All in the reference camera's frame: X = D * K_ref^-1 (col + 0.5, row + 0.5, 1), and
// X_j = A X + a the point in view j's camera frame, C view j's centre in the reference's frame.
// view_params, per view (20 floats): K_j A (9, row-major), the last row of A (3), K_j a (3),
// a.z (1), K_ref C (3), 0.
// view_dims, per view (6 ints): width and height of j's depth map, offset of the map in
// depth_maps (2 ints: hm_plane_offset), and the pixel (col0, row0) of the whole map that is the
// map's pixel (0, 0) (a map of part of it: FusionView::CropToDepth). A point is seen when
// X_j.z > 0 and its projection (SfM convention: pixel (c, r) covers [c, c+1) x [r, r+1)) falls
// inside the map; j's surface on the ray is
// S = C + (X - C) * depth_j / X_j.z, projected back by K_ref.
// ref_params (9 floats): K_ref^-1 (row-major).

#include "common.clh"

inline float3 MatVec(__global const float* m, float3 x) {
  return (float3)(m[0] * x.x + m[1] * x.y + m[2] * x.z, m[3] * x.x + m[4] * x.y + m[5] * x.z,
                  m[6] * x.x + m[7] * x.y + m[8] * x.z);
}

// LABEL_CHUNK (build option): labels per work-item; the quantities of a pixel and a view that do
// not depend on the depth are computed once for them.
#ifndef LABEL_CHUNK
#error "LABEL_CHUNK must be defined"
#endif

// Global size (width, height, ceil(num_labels / LABEL_CHUNK)). Per pixel p and view j, with
// r = K_ref^-1 (col + 0.5, row + 0.5, 1) (so X = D r): X_j = D (A r) + a, its projection
// K_j X_j = D (K_j A r) + K_j a, and j's surface S projected back by K_ref:
// K_ref S = K_ref C + (D (col + 0.5, row + 0.5, 1) - K_ref C) depth_j / X_j.z.
__kernel void geometric_prior(int width, int height, __global const float* ref_params,
                              __global const float* depth_maps,
                              __global const float* view_params,
                              __global const int* view_dims, int num_views, int num_labels,
                              __global const float* label_base, int has_base,
                              __global const uchar* active, int has_active, float label_step,
                              float depth_a, float depth_b, int inverse_depth,
                              float max_error_px, float level0_px_per_grid_px,
                              float per_view_weight, __global float* volume) {
  const int col = get_global_id(0);
  const int row = get_global_id(1);
  const int k0 = get_global_id(2) * LABEL_CHUNK;
  if (col >= width || row >= height) return;
  const int p = row * width + col;
  if (has_active && !active[p]) return;
  const int count = min(LABEL_CHUNK, num_labels - k0);
  const float base = has_base ? label_base[p] : 0.0f;
  float depth[LABEL_CHUNK], total[LABEL_CHUNK];
  for (int i = 0; i < count; ++i) {
    const float t = depth_a + depth_b * (base + (float)(k0 + i) * label_step);
    depth[i] = inverse_depth ? 1.0f / t : t;
    total[i] = 0.0f;
  }
  const float2 centre = (float2)((float)col + 0.5f, (float)row + 0.5f);
  const float3 pixel = (float3)(centre, 1.0f);
  const float3 ray = MatVec(ref_params, pixel);
  for (int j = 0; j < num_views; ++j) {
    __global const float* params = view_params + 20 * j;
    const float3 k_a_ray = MatVec(params, ray);
    const float a_ray_z = params[9] * ray.x + params[10] * ray.y + params[11] * ray.z;
    const float3 k_a = (float3)(params[12], params[13], params[14]);
    const float a_z = params[15];
    const float3 k_ref_c = (float3)(params[16], params[17], params[18]);
    __global const int* dims = view_dims + 6 * j;
    const int map_width = dims[0], map_height = dims[1], col0 = dims[4], row0 = dims[5];
    __global const float* map = depth_maps + hm_plane_offset(dims);
    for (int i = 0; i < count; ++i) {
      const float d = depth[i];
      float error = max_error_px;
      const float xj_z = d * a_ray_z + a_z;
      if (xj_z > 0.0f) {
        const float3 uvw = d * k_a_ray + k_a;
        const float u = uvw.x / uvw.z, w = uvw.y / uvw.z;
        // The whole map's pixel, then the part's: whole pixels, so that a part is read exactly
        // where the whole was.
        if (u >= 0.0f && w >= 0.0f && u < (float)(col0 + map_width) &&
            w < (float)(row0 + map_height) && (int)u >= col0 && (int)w >= row0) {
          const float map_depth = map[((int)w - row0) * map_width + (int)u - col0];
          if (map_depth > 0.0f) {
            const float3 back = k_ref_c + (d * pixel - k_ref_c) * (map_depth / xj_z);
            if (back.z > 0.0f) {
              const float e = length(back.xy / back.z - centre) * level0_px_per_grid_px;
              error = min(e, max_error_px);
            }
          }
        }
      }
      total[i] += error;
    }
  }
  for (int i = 0; i < count; ++i) {
    volume[(size_t)(k0 + i) * width * height + p] += per_view_weight * total[i] / max_error_px;
  }
}
