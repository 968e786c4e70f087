// The geometric pass's prior (src/stereo/geometric_prior.h): for pixel p of the reference's grid
// and label v = (has_base ? label_base[p] : 0) + k * label_step, at depth D(v), where
// (has_active ? active[p] : 1) is non-zero,
//   volume[k][p] += per_view_weight * sum_j min(e_j, max_error_px) / max_error_px,
// e_j COLMAP's forward-backward reprojection error through view j's depth map (in level-0
// pixels: the grid's error times level0_px_per_grid_px), max_error_px where view j does not see
// the point or has no depth there.
// All in the reference camera's frame: X = D * K_ref^-1 (col + 0.5, row + 0.5, 1).
// view_params, per view (24 floats): A (9, row-major), a (3) with X_j = A X + a the point in
// view j's camera frame; K_j (9, row-major); C (3), view j's centre in the reference's frame.
// view_dims, per view (4 ints): width and height of j's depth map, offset of the map in
// depth_maps, 0. A point is seen when X_j.z > 0 and its projection (SfM convention: pixel
// (c, r) covers [c, c+1) x [r, r+1)) falls inside the map; j's surface on the ray is
// S = C + (X - C) * depth_j / X_j.z, projected back by K_ref.
// ref_params (18 floats): K_ref^-1, K_ref (row-major).

inline float3 MatVec(__global const float* m, float3 x) {
  return (float3)(m[0] * x.x + m[1] * x.y + m[2] * x.z, m[3] * x.x + m[4] * x.y + m[5] * x.z,
                  m[6] * x.x + m[7] * x.y + m[8] * x.z);
}

// Global size (width, height, num_labels).
__kernel void geometric_prior(int width, int height, __global const float* ref_params,
                              __global const float* depth_maps,
                              __global const float* view_params,
                              __global const int* view_dims, int num_views,
                              __global const float* label_base, int has_base,
                              __global const uchar* active, int has_active, float label_step,
                              float depth_a, float depth_b, int inverse_depth,
                              float max_error_px, float level0_px_per_grid_px,
                              float per_view_weight, __global float* volume) {
  const int col = get_global_id(0);
  const int row = get_global_id(1);
  const int k = get_global_id(2);
  if (col >= width || row >= height) return;
  const int p = row * width + col;
  if (has_active && !active[p]) return;
  const float v = (has_base ? label_base[p] : 0.0f) + (float)k * label_step;
  const float t = depth_a + depth_b * v;
  const float depth = inverse_depth ? 1.0f / t : t;
  const float2 centre = (float2)((float)col + 0.5f, (float)row + 0.5f);
  const float3 x = depth * MatVec(ref_params, (float3)(centre, 1.0f));
  float total = 0.0f;
  for (int j = 0; j < num_views; ++j) {
    __global const float* params = view_params + 24 * j;
    float error = max_error_px;
    const float3 xj = MatVec(params, x) + (float3)(params[9], params[10], params[11]);
    if (xj.z > 0.0f) {
      const float3 uvw = MatVec(params + 12, xj);
      const float u = uvw.x / uvw.z, w = uvw.y / uvw.z;
      const int map_width = view_dims[4 * j], map_height = view_dims[4 * j + 1];
      if (u >= 0.0f && w >= 0.0f && u < (float)map_width && w < (float)map_height) {
        const float map_depth =
            depth_maps[view_dims[4 * j + 2] + (int)w * map_width + (int)u];
        if (map_depth > 0.0f) {
          const float3 c = (float3)(params[21], params[22], params[23]);
          const float3 s = c + (x - c) * (map_depth / xj.z);
          const float3 back = MatVec(ref_params + 9, s);
          if (back.z > 0.0f) {
            const float e = length(back.xy / back.z - centre) * level0_px_per_grid_px;
            error = min(e, max_error_px);
          }
        }
      }
    }
    total += error;
  }
  volume[k * width * height + p] += per_view_weight * total / max_error_px;
}
