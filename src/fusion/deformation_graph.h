#pragma once
// Stage 3 of template fusion: the refined template. The coarse template is deformed towards
// every depth map along that map's lines of sight by an embedded deformation graph (Sumner,
// Schmid, Pauly 2007) registered non-rigidly as in Li, Adams, Guibas, Pauly 2009: graph nodes
// sampled on the template, each with an affine transform (A_j, t_j); a vertex v moves to
// sum_j w_j(v) [A_j (v - g_j) + g_j + t_j] over its nearest nodes. Energy per round:
//   E = w_fit E_fit + w_rigid E_rigid + w_smooth E_smooth
//   E_fit    = mean over vertices of |v' - q(v)|^2, q(v) = the mean over the views that see v
//              of the point of that view's surface on its line of sight through v;
//   E_rigid  = mean over nodes of Rot(A_j) (columns orthonormal, Sumner et al. Eq. 4);
//   E_smooth = mean over graph edges of |A_j (g_k - g_j) + g_j + t_j - (g_k + t_k)|^2.
// Lengths are measured in octree cells, so the weights do not depend on the scene's scale.
// After each round the deformed surface becomes the rest state and the regularisation
// weights are multiplied by regularization_decay (method.md section 3.2).

#include <vector>

#include "hairmvs/template_fusion.h"
#include "src/fusion/fusion_view.h"

namespace hairmvs {

struct RegistrationStats {
  int num_nodes = 0;
  int num_edges = 0;
  // Per round, before its solve: RMS distance (m) from the fit vertices to their targets,
  // and how many vertices had a target.
  std::vector<double> fit_rms_m;
  std::vector<int> num_fit_vertices;
};

// Deforms `mesh` in place (vertices and normals). Views need depth maps only.
RegistrationStats RefineTemplate(const std::vector<FusionView>& views,
                                 const TemplateFusionOptions& options, double cell_m,
                                 FusionMesh* mesh);

}  // namespace hairmvs
