// Commands on a COLMAP dense workspace as a whole.

#include <cstdio>
#include <string>

#include "colmap_ext/workspace_info.h"
#include "src/cli/command_registry.h"
#include "src/core/option_parser.h"
#include "src/core/timer.h"

namespace hairmvs {
namespace {

int RunWorkspaceInfo(int argc, char** argv) {
  std::string workspace_path;
  std::string mask_path;
  SourceViewOptions options;
  OptionParser parser("workspace_info",
                      "Lists the views, cameras, masks, source views (and why) and depth ranges "
                      "of a COLMAP dense workspace.");
  parser.Add("workspace_path", &workspace_path, "COLMAP dense workspace (image_undistorter)",
             true);
  parser.Add("mask_path", &mask_path,
             "folder of masks <image name>.png (default: <workspace>/masks if present)");
  parser.AddSection("SourceViews", &options);
  if (!parser.Parse(argc, argv)) return 0;
  Timer timer;
  const WorkspaceInfo info = ComputeWorkspaceInfo(workspace_path, mask_path, options);
  std::printf("%s", info.Report().c_str());
  std::printf("Total run time %.3f s (peak memory %.0f MiB)\n", timer.ElapsedSeconds(),
              PeakResidentMemoryMiB());
  return 0;
}

}  // namespace

HAIRMVS_REGISTER_COMMAND("workspace_info", RunWorkspaceInfo,
                         "views, cameras, masks, source views (and why), depth ranges of a "
                         "dense workspace");

}  // namespace hairmvs

