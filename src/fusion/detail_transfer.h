#pragma once
// Stage 4 of template fusion: the depth maps' high frequencies put back onto the refined
// template as offsets along its vertex normals (a linear deformation, method.md section 3.3),
// and the mesh's colours sampled from the images.

#include <vector>

#include "hairmvs/template_fusion.h"
#include "src/fusion/fusion_view.h"

namespace hairmvs {

struct DetailStats {
  int num_vertices_with_detail = 0;
  double median_abs_offset_m = 0;
};

// For each vertex v with unit normal n and each view that sees it within
// max_detail_view_angle_deg of n: q = the view's surface point on its line of sight through
// v; if that surface is locally parallel to the template, the offset along n that reaches it
// is s = (q - v) . n (the line of sight crosses the offset plane at q). The vertex moves by
// the median of s over the views (|s| <= max_detail_offset_cells), robust to a view that
// sees another layer; with detail_smoothness_weight > 0, those medians are the targets of
// SmoothDetailOffsets.
DetailStats TransferDetail(const std::vector<FusionView>& views,
                           const TemplateFusionOptions& options, double cell_m,
                           FusionMesh* mesh);

// The offsets as one linear least-squares problem (TemplateFusionOptions::
// detail_smoothness_weight): minimises sum_i (s_i - t_i)^2 over the vertices with a target t_i
// (*offsets[i], NaN where none) plus `weight` times sum (s_i - s_j)^2 over the mesh's edges, and
// writes s into *offsets. A vertex with no target in its part of the mesh stays NaN.
void SmoothDetailOffsets(const FusionMesh& mesh, double weight, std::vector<double>* offsets);

// Vertex colours: the mean over the views that see a vertex (facing it, depth agreeing
// within visibility_depth_tolerance), weighted by the cosine of the viewing angle. Grey
// where no view with colours sees it.
void ColorizeMesh(const std::vector<FusionView>& views, const TemplateFusionOptions& options,
                  FusionMesh* mesh);

}  // namespace hairmvs
