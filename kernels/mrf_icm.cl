// Checkerboard iterated conditional modes on the depth-label MRF (src/mrf/mrf.h), OpenCL C 1.2.
//
// Tunable (build option): NUM_LABELS, the number of labels L.
// Layouts: cost is [label][row][col] (L * H * W floats); offset, weight_right, weight_down and
// labels are H * W. value(p, l) = offset[p] + l * step.
//
// icm_colour: every pixel with (row + col) % 2 == colour takes the label minimising its local
// energy (data + the 4 pairwise terms, neighbours fixed; ties keep the current label). Pixels
// of one colour only have neighbours of the other colour, so they update independently and
// the result equals the sequential CPU reference PolishWithIcm (same float arithmetic order).
// Sets *changed = 1 when a label changed (all writers write the same value).

#pragma OPENCL FP_CONTRACT OFF

#ifndef NUM_LABELS
#error "NUM_LABELS must be defined"
#endif

#include "mrf_checkerboard.clh"

__kernel void icm_colour(__global const float* cost, __global const float* offset, float step,
                         __global const float* weight_right, __global const float* weight_down,
                         float truncation, int width, int height, int colour,
                         __global int* labels, __global int* changed) {
  int row, col;
  const int p = mrf_checkerboard_pixel(width, height, colour, &row, &col);
  if (p < 0) return;
  const int n = width * height;
  // Neighbour values and weights (weight 0 where there is no neighbour).
  float nv[4];
  float nw[4];
  nv[0] = col > 0 ? offset[p - 1] + (float)labels[p - 1] * step : 0.0f;
  nw[0] = col > 0 ? weight_right[p - 1] : 0.0f;
  nv[1] = col + 1 < width ? offset[p + 1] + (float)labels[p + 1] * step : 0.0f;
  nw[1] = col + 1 < width ? weight_right[p] : 0.0f;
  nv[2] = row > 0 ? offset[p - width] + (float)labels[p - width] * step : 0.0f;
  nw[2] = row > 0 ? weight_down[p - width] : 0.0f;
  nv[3] = row + 1 < height ? offset[p + width] + (float)labels[p + width] * step : 0.0f;
  nw[3] = row + 1 < height ? weight_down[p] : 0.0f;
  const int current = labels[p];
  int best_label = current;
  float best = INFINITY;
  for (int pass = 0; pass <= NUM_LABELS; ++pass) {
    // pass 0 evaluates the current label, so that ties keep it.
    const int l = pass == 0 ? current : pass - 1;
    const float v = offset[p] + (float)l * step;
    float e = cost[l * n + p];
    for (int k = 0; k < 4; ++k) {
      const float d = v - nv[k];
      e += nw[k] * fmin(d * d, truncation);
    }
    if (e < best) {
      best = e;
      best_label = l;
    }
  }
  if (best_label != current) {
    labels[p] = best_label;
    *changed = 1;
  }
}
