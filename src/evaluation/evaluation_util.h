#pragma once
// Small helpers shared by the evaluators: distance statistics and the median filter.

#include <string>
#include <vector>

#include "hairmvs/evaluation.h"
#include "src/core/float_map.h"

namespace hairmvs {

// Mean, median and 90th percentile of distances given in metres, reported in mm.
DistanceStats SummarizeDistances(std::vector<double> distances_m);
// Percentile q in [0, 1] (nearest rank on the sorted values); 0 for an empty vector.
double Percentile(std::vector<double> values, double q);
double Mean(const std::vector<double>& values);

// k x k median of the valid (> 0) depths around each valid pixel (the median of an even
// count is the mean of the two middle values); invalid pixels stay 0. k odd.
// include_invalid: a plain median over every pixel of the window (zeros included, the
// window clamped at the image border), computed for every pixel, like
// scipy.ndimage.median_filter(depth, k) up to its border rule.
FloatMap MedianFilterValidDepths(const FloatMap& depth, int k, bool include_invalid = false);

// "Section.field" checks shared by the option structs.
bool CheckImageNames(const std::vector<std::string>& names, std::string* error);

}  // namespace hairmvs
