#pragma once
// Stage 2 of template fusion: the coarse template, by screened Poisson surface reconstruction
// (Kazhdan and Hoppe, through Open3D) at a low octree depth, trimmed where it has no data.

#include "hairmvs/template_fusion.h"
#include "src/fusion/fusion_view.h"

namespace hairmvs {

// The edge of one octree cell: Poisson's cube is the points' bounding box's largest side
// times poisson_scale, split 2^poisson_depth times.
double PoissonCellSize(const FusionPoints& points, const TemplateFusionOptions& options);

// Poisson at options.poisson_depth on `samples` (with normals), then trimmed: faces farther
// than trim_distance_cells from every sample, and components smaller than
// min_component_fraction of the largest, are removed (never closer than
// trim_min_sample_spacings times `sample_spacing_m`, the voxel size the samples were merged
// on). Empty if nothing is left.
FusionMesh PoissonTemplate(const FusionPoints& samples, const TemplateFusionOptions& options,
                           double cell_m, double sample_spacing_m);

// Loop subdivision (Open3D), `iterations` times.
FusionMesh SubdivideLoop(const FusionMesh& mesh, int iterations);

}  // namespace hairmvs
