#pragma once
// Stage 1 of template fusion: points from all depth maps, with normals, colours and the views
// that see them, merged on a voxel grid.

#include <vector>

#include "hairmvs/template_fusion.h"
#include "src/fusion/fusion_view.h"

namespace hairmvs {

// Median over the views of the median pixel footprint (depth / fx) of the valid pixels: the
// scale in which the pixel-based options are expressed.
double MedianPixelFootprint(const std::vector<FusionView>& views);

// Back-projects every point_stride_px-th valid pixel of every view (SfM pixel centres), with
// its world normal and colour; a point is seen by every view where it projects within the
// depth map and agrees with that view's depth (visibility_depth_tolerance); points seen by
// fewer than min_num_visible_views views are dropped. Views need normals.
FusionPoints ExtractFusionPoints(const std::vector<FusionView>& views,
                                 const TemplateFusionOptions& options, int* num_input_points);

// Averages the points falling into the same cubic voxel of `voxel_size_m`: position, normal
// (renormalised), colour; the visibility is the union.
FusionPoints VoxelMergePoints(const FusionPoints& points, double voxel_size_m);

}  // namespace hairmvs
