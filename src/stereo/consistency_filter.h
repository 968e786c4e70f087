#pragma once
// Geometric consistency filter of depth maps (COLMAP's patch_match_stereo `filter` with
// `geom_consistency`, in its simplest form): a pixel keeps its depth only where enough other
// views, at the pixel its back-projected point projects to, have a depth that agrees. Pixels
// whose depth is wrong (hair seen through gaps, matching on the wrong layer) rarely agree with
// an independent estimate from another viewpoint.

#include <cstdint>
#include <vector>

#include "src/core/float_map.h"
#include "src/fusion/fusion_view.h"

namespace hairmvs {

// 64-bit: a run sums them over all its views (hundreds of 24-Mpixel maps pass 2^31).
struct ConsistencyFilterStats {
  int64_t num_checked = 0;  // valid pixels of the reference
  int64_t num_kept = 0;
};

// COLMAP's forward-backward reprojection error: the point `world` (seen at image point
// `centre` of the camera K, R, t) is taken to `other`'s surface along other's line of sight (the
// depth of the pixel it projects to, FusionView::SurfaceOnRay), which is projected back into the
// camera; the distance in pixels to `centre`. False where `other` does not see the point, has no
// depth there, or its surface point lies behind the camera.
bool ForwardBackwardErrorPx(const FusionView& other, const Eigen::Vector3d& world,
                            const Eigen::Matrix3d& K, const Eigen::Matrix3d& R,
                            const Eigen::Vector3d& t, const Eigen::Vector2d& centre,
                            double* error_px);

// Returns `ref.depth` with 0 where fewer than `min_consistent_views` of `others` agree. A view
// agrees when the pixel's point, scaled along that view's line of sight to the view's depth at
// the pixel it projects to (SfM convention, nearest pixel), projects back into the reference
// within max_reprojection_error_px of the pixel's centre (COLMAP's forward-backward
// reprojection error, so the tolerance in depth scales with the baseline). A view whose ray to
// the point meets the reference's at less than `min_triangulation_angle_deg` does not count
// (COLMAP's filter_min_triangulation_angle): beside the reference, it reprojects any depth onto
// the pixel. Maps may differ in size from the images as long as each K matches its map, and
// hold part of them (FusionView::CropToDepth): the result is then of the reference's part.
// The error is in the reference's pixels, as COLMAP's. Counted in the coarser view's pixels
// instead (the tolerance times the reference's scale over the other view's at the point, where
// above 1; a prototype at stop 60, not kept): a 960 px pair whose sources are 480 px views
// (scripts/mixed_scale_workspace.py) 91.2% -> 93.5% complete at 2.72 -> 2.76 mm, but
// synth_handheld's per-pixel median 4.71 -> 4.81 mm, its 3D median 0.592 -> 0.613 mm.
FloatMap FilterDepthMapByConsistency(const FusionView& ref,
                                     const std::vector<const FusionView*>& others,
                                     double max_reprojection_error_px, int min_consistent_views,
                                     double min_triangulation_angle_deg,
                                     ConsistencyFilterStats* stats = nullptr);

}  // namespace hairmvs
