#pragma once
// EvaluateDepthMaps and EvaluateMesh with the true strands' index built by the caller (tests and
// tools that evaluate several workspaces of one data set index the strands once: ~25 s for 40 000
// strands at 0.2 mm).

#include <string>

#include "hairmvs/evaluation.h"
#include "src/evaluation/ground_truth.h"

namespace hairmvs {

// `strands` must index ground_truth_path's strands; options.strand_spacing_m is then unused.
DepthEvaluationResult EvaluateDepthMaps(const std::string& workspace_path,
                                        const std::string& ground_truth_path,
                                        const DepthEvaluationOptions& options,
                                        const StrandDistance& strands,
                                        StageTimings* timings = nullptr);
MeshEvaluationResult EvaluateMesh(const std::string& mesh_path,
                                  const std::string& ground_truth_path,
                                  const std::string& workspace_path,
                                  const MeshEvaluationOptions& options,
                                  const StrandDistance& strands,
                                  StageTimings* timings = nullptr);

}  // namespace hairmvs
