#pragma once
// The template-fusion pipeline on in-memory views (no files): what RunTemplateFusion runs
// after reading a workspace, and what the tests call with synthetic depth maps.

#include <vector>

#include "hairmvs/template_fusion.h"
#include "src/core/timer.h"
#include "src/fusion/deformation_graph.h"
#include "src/fusion/detail_transfer.h"
#include "src/fusion/fusion_view.h"

namespace hairmvs {

struct FusionOutput {
  FusionPoints fused;  // visible_views index `views`
  FusionMesh coarse;   // Poisson, trimmed
  FusionMesh refined;  // subdivided and registered to the depth maps
  FusionMesh final_mesh;  // refined + detail, with colours
  double cell_m = 0;
  double footprint_m = 0;
  int num_input_points = 0;
  int num_poisson_points = 0;
  RegistrationStats registration;
  DetailStats detail;
};

// Runs the four stages; `timings` (may be null) gets one entry per stage. Throws
// hairmvs::Error when the views give no points.
FusionOutput FuseViews(const std::vector<FusionView>& views, const TemplateFusionOptions& options,
                       StageTimings* timings);

}  // namespace hairmvs
