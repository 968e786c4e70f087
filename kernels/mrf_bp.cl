// Loopy min-sum belief propagation on the 4-connected depth-label MRF (src/mrf/mrf.h),
// checkerboard schedule (Felzenszwalb and Huttenlocher 2006), OpenCL C 1.2.
//
// Tunable (build option): NUM_LABELS, the number of labels L.
// Layouts: cost is [label][row][col] (L * H * W floats); offset, weight_right, weight_down and
// labels are H * W; msg is [slot][label][row][col] (4 * L * H * W floats): the message a pixel
// received from its left (slot 0), right (1), upper (2) and lower (3) neighbour.
// value(p, l) = offset[p] + l * step.
//
// bp_colour: every pixel p with (row + col) % 2 == colour sends its 4 messages
//   m_{p->q}(b) = min_a [cost(p, a) + sum of p's messages except q's](a) + V_pq(a, b)
// (normalised to min 0) into its neighbours' slots. Pixels of one colour only read their own
// slots and write slots of the other colour, so they update independently; the result equals
// the sequential CPU reference SolveBeliefPropagationCpu (same float arithmetic order).
// bp_labels: label(p) = argmin_a cost(p, a) + sum of p's 4 messages, ties to the lowest label.

#pragma OPENCL FP_CONTRACT OFF

#include "mrf_checkerboard.clh"
#include "mrf_path_min.clh"

__kernel void bp_colour(__global const float* cost, __global const float* offset, float step,
                        __global const float* weight_right, __global const float* weight_down,
                        float truncation, int width, int height, int colour,
                        __global float* msg) {
  int row, col;
  const int p = mrf_checkerboard_pixel(width, height, colour, &row, &col);
  if (p < 0) return;
  const int n = width * height;
  float h[NUM_LABELS];
  float prev[NUM_LABELS];
  float m[NUM_LABELS];
  for (int a = 0; a < NUM_LABELS; ++a) {
    h[a] = cost[a * n + p] + msg[(0 * NUM_LABELS + a) * n + p] +
           msg[(1 * NUM_LABELS + a) * n + p] + msg[(2 * NUM_LABELS + a) * n + p] +
           msg[(3 * NUM_LABELS + a) * n + p];
  }
  // k: 0 = to the left neighbour, 1 = right, 2 = up, 3 = down.
  for (int k = 0; k < 4; ++k) {
    int q;
    float w;
    if (k == 0) {
      if (col == 0) continue;
      q = p - 1;
      w = weight_right[p - 1];
    } else if (k == 1) {
      if (col + 1 == width) continue;
      q = p + 1;
      w = weight_right[p];
    } else if (k == 2) {
      if (row == 0) continue;
      q = p - width;
      w = weight_down[p - width];
    } else {
      if (row + 1 == height) continue;
      q = p + width;
      w = weight_down[p];
    }
    // The message to q excludes what q sent: q is p's neighbour in direction k, so its message
    // sits in p's slot k; p's message lands in q's opposite slot (k ^ 1).
    float prev_min = INFINITY;
    for (int a = 0; a < NUM_LABELS; ++a) {
      prev[a] = h[a] - msg[(k * NUM_LABELS + a) * n + p];
      prev_min = fmin(prev_min, prev[a]);
    }
    mrf_path_min(prev, prev_min, step, offset[q] - offset[p], w, truncation, m);
    float m_min = INFINITY;
    for (int b = 0; b < NUM_LABELS; ++b) m_min = fmin(m_min, m[b]);
    const int slot = k ^ 1;
    for (int b = 0; b < NUM_LABELS; ++b) msg[(slot * NUM_LABELS + b) * n + q] = m[b] - m_min;
  }
}

__kernel void bp_labels(__global const float* cost, __global const float* msg, int num_pixels,
                        __global int* labels) {
  const int p = get_global_id(0);
  const int n = num_pixels;
  if (p >= n) return;
  float best = INFINITY;
  int best_label = 0;
  for (int a = 0; a < NUM_LABELS; ++a) {
    const float belief = cost[a * n + p] + msg[(0 * NUM_LABELS + a) * n + p] +
                         msg[(1 * NUM_LABELS + a) * n + p] + msg[(2 * NUM_LABELS + a) * n + p] +
                         msg[(3 * NUM_LABELS + a) * n + p];
    if (belief < best) {
      best = belief;
      best_label = a;
    }
  }
  labels[p] = best_label;
}
