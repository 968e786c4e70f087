// Semi-global matching on the depth-label MRF (src/mrf/semi_global.h), OpenCL C 1.2.
//
// Tunable (build option): NUM_LABELS, the number of labels L (private arrays of 2 L floats).
// Layouts: cost and sum are [row][col][label] (H * W * L floats), so that the labels of a pixel,
// which a path reads and writes together, share cache lines; offset, weight are H * W.
// value(p, l) = offset[p] + l * step. weight[e] is the edge weight of this direction's edge
// type, indexed by the edge's upper (horizontal edges: left) pixel e.
//
// sgm_path: one work-item per scanline path of direction (dx, dy); adds L_r(p, .) into sum.
// Paths of one direction never share a pixel, so the additions do not race; directions run as
// successive kernels on the in-order queue. The arithmetic order matches SolveSemiGlobalCpu.
// sgm_argmin: label(p) = argmin_b sum(p, b), ties to the lowest label.

#pragma OPENCL FP_CONTRACT OFF

#include "mrf_path_min.clh"

__kernel void sgm_path(__global const float* cost, __global const float* offset, float step,
                       __global const float* weight, float truncation, int width, int height,
                       int dx, int dy, int num_paths, __global float* sum) {
  const int k = get_global_id(0);
  if (k >= num_paths) return;
  int col;
  int row;
  if (dy == 0) {
    row = k;
    col = dx > 0 ? 0 : width - 1;
  } else if (dx == 0) {
    col = k;
    row = dy > 0 ? 0 : height - 1;
  } else if (k < width) {
    col = k;
    row = dy > 0 ? 0 : height - 1;
  } else {
    const int j = k - width + 1;
    col = dx > 0 ? 0 : width - 1;
    row = dy > 0 ? j : height - 1 - j;
  }
  float prev[NUM_LABELS];
  float cur[NUM_LABELS];
  float m[NUM_LABELS];
  int p = row * width + col;
  float prev_min = INFINITY;
#pragma unroll
  for (int b = 0; b < NUM_LABELS; ++b) {
    prev[b] = cost[p * NUM_LABELS + b];
    prev_min = fmin(prev_min, prev[b]);
    sum[p * NUM_LABELS + b] += prev[b];
  }
  float prev_offset = offset[p];
  const int upper_is_prev = dy > 0 || (dy == 0 && dx > 0);
  for (;;) {
    col += dx;
    row += dy;
    if (col < 0 || col >= width || row < 0 || row >= height) break;
    const int q = p;
    p = row * width + col;
    const float w = weight[upper_is_prev ? q : p];
    const float cur_offset = offset[p];
    mrf_path_min(prev, prev_min, step, cur_offset - prev_offset, w, truncation, m);
    float cur_min = INFINITY;
    for (int b = 0; b < NUM_LABELS; ++b) {
      cur[b] = cost[p * NUM_LABELS + b] + (m[b] - prev_min);
      cur_min = fmin(cur_min, cur[b]);
    }
#pragma unroll
    for (int b = 0; b < NUM_LABELS; ++b) {
      prev[b] = cur[b];
      sum[p * NUM_LABELS + b] += cur[b];
    }
    prev_min = cur_min;
    prev_offset = cur_offset;
  }
}

__kernel void sgm_argmin(__global const float* sum, int num_pixels, __global int* labels) {
  const int p = get_global_id(0);
  if (p >= num_pixels) return;
  float best = sum[p * NUM_LABELS];
  int best_label = 0;
  for (int b = 1; b < NUM_LABELS; ++b) {
    const float s = sum[p * NUM_LABELS + b];
    if (s < best) {
      best = s;
      best_label = b;
    }
  }
  labels[p] = best_label;
}
