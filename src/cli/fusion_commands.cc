// hairmvs template_fusion: the depth maps of a workspace merged into one hair surface
// (method.md section 3): fused.ply (+ .vis) and meshed-hair.ply in the workspace root.

#include <cstdio>
#include <string>

#include "hairmvs/template_fusion.h"
#include "src/cli/command_registry.h"
#include "src/core/logging.h"
#include "src/core/option_parser.h"
#include "src/core/timer.h"

namespace hairmvs {
namespace {

int RunTemplateFusionCommand(int argc, char** argv) {
  std::string workspace_path;
  TemplateFusionOptions options;
  OptionParser parser(
      "template_fusion",
      "Merges the depth maps of a dense workspace (stereo/depth_maps/*.{geometric,photometric}"
      ".bin with their normal maps) into fused.ply + fused.ply.vis (as colmap stereo_fusion "
      "writes them) and meshed-hair.ply: a coarse Poisson template (octree depth 6), refined "
      "towards every depth map by an embedded deformation graph, plus the depth maps' detail.");
  parser.Add("workspace_path", &workspace_path, "dense workspace (COLMAP layout)", true);
  parser.AddSection("TemplateFusion", &options);
  if (!parser.Parse(argc, argv)) return 0;
  std::string error;
  THROW_IF(!options.Check(&error), "invalid option: " << error);
  StageTimings timings;
  const TemplateFusionResult result = RunTemplateFusion(workspace_path, options, &timings);
  std::printf("%s\n%s", result.BriefReport().c_str(), RunSummary(timings).c_str());
  return 0;
}

}  // namespace

HAIRMVS_REGISTER_COMMAND("template_fusion", RunTemplateFusionCommand,
                         "merge depth maps into fused.ply and meshed-hair.ply (template fusion)");

}  // namespace hairmvs
