// Orientation field filter bank (Luo et al. 2012, Section 2; method.md section 1).
//
// orientation_field: one work-item = VEC consecutive pixels of one row, all angles.
// For each block of BLOCK consecutive angles it walks the tap pairs {d, -d} of the union of
// the block's filter supports: one pair of unaligned vector loads and one add, then BLOCK
// multiply-adds into accumulators held in registers (the filters are point-symmetric,
// K(-d) = K(d), which halves the loads and multiplies). After each block it updates the
// running max |response|, its angle index and the max signed response.
//
// Build options (all required):
//   -D VEC=8|16       pixels per work-item (float8 / float16)
//   -D BLOCK=n        angles per block (1..32)
//
// Arguments:
//   padded         the grey image padded by `pad` pixels on every side with replicated edges;
//                  row stride padded_stride; pixel (x, y) at [(y + pad) * padded_stride + x + pad].
//                  padded_stride >= out_stride + 2 pad, so a work-item may read past x = width.
//   tap_offsets    per tap pair: dy * padded_stride + dx (the representative d of {d, -d}).
//   tap_begin      num_blocks + 1 entries: block b uses taps [tap_begin[b], tap_begin[b + 1]).
//   weights        [tap][BLOCK]: the weight of each angle of the block for that pair (the
//                  centre tap's weight is halved, as it is loaded twice).
//   mask           width x height at row stride out_stride; > 0 = valid.
//   out            2 planes (Re O, Im O) of out_stride x height floats each.
//   num_blocks, num_orientations, width, height, out_stride, gamma,
//   min_positive_ratio   O = 0 unless max signed response > min_positive_ratio * max |response|
//                        (-1: dark strands too, every pixel with a response).
// Theta_k = k pi / num_orientations (from +x towards +y); angles k >= num_orientations of the
// last block carry zero weights and are never chosen.

#define HM_CAT_(a, b) a##b
#define HM_CAT(a, b) HM_CAT_(a, b)
#define floatV HM_CAT(float, VEC)
#define intV HM_CAT(int, VEC)
#define vloadV HM_CAT(vload, VEC)
#define vstoreV HM_CAT(vstore, VEC)

__kernel void orientation_field(__global const float* restrict padded, int padded_stride, int pad,
                                __global const int* restrict tap_offsets,
                                __global const int* restrict tap_begin,
                                __global const float* restrict weights,
                                __global const float* restrict mask,
                                __global float* restrict out, int num_blocks,
                                int num_orientations, int width, int height, int out_stride,
                                float gamma, float min_positive_ratio) {
  const int x0 = get_global_id(0) * VEC;
  const int y = get_global_id(1);
  if (y >= height || x0 >= out_stride) return;
  __global const float* center = padded + (y + pad) * padded_stride + x0 + pad;

  floatV best_abs = (floatV)(-1.0f);
  floatV best_index = (floatV)(0.0f);
  floatV max_signed = (floatV)(-INFINITY);

  for (int b = 0; b < num_blocks; ++b) {
    floatV acc[BLOCK];
#pragma unroll
    for (int j = 0; j < BLOCK; ++j) acc[j] = (floatV)(0.0f);
    const int end = tap_begin[b + 1];
    for (int t = tap_begin[b]; t < end; ++t) {
      const int offset = tap_offsets[t];
      const floatV s = vloadV(0, center + offset) + vloadV(0, center - offset);
      __global const float* w = weights + t * BLOCK;
#pragma unroll
      for (int j = 0; j < BLOCK; ++j) acc[j] = mad((floatV)(w[j]), s, acc[j]);
    }
#pragma unroll
    for (int j = 0; j < BLOCK; ++j) {
      const int k = b * BLOCK + j;
      if (k < num_orientations) {
        const floatV magnitude = fabs(acc[j]);
        const intV better = isgreater(magnitude, best_abs);  // strict: first max wins
        best_abs = select(best_abs, magnitude, better);
        best_index = select(best_index, (floatV)((float)k), better);
        max_signed = fmax(max_signed, acc[j]);
      }
    }
  }

  // O = F exp(2 i Theta), F = max|response|^gamma, for bright strands only (Eq. 1: max signed
  // response > 0, with a relative tolerance for responses that are zero up to rounding) or, with
  // a ratio of -1, for dark ones too.
  const floatV confidence = pow(fmax(best_abs, (floatV)(0.0f)), (floatV)(gamma));
  const floatV two_theta = best_index * (2.0f * M_PI_F / (float)num_orientations);
  floatV cos_two_theta;
  const floatV sin_two_theta = sincos(two_theta, &cos_two_theta);
  const floatV m = vloadV(0, mask + y * out_stride + x0);
  const intV valid =
      isgreater(max_signed, min_positive_ratio * best_abs) & isgreater(m, (floatV)(0.0f));
  const floatV re = select((floatV)(0.0f), confidence * cos_two_theta, valid);
  const floatV im = select((floatV)(0.0f), confidence * sin_two_theta, valid);
  vstoreV(re, 0, out + y * out_stride + x0);
  vstoreV(im, 0, out + out_stride * height + y * out_stride + x0);
}
