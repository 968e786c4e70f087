// Commands on a COLMAP dense workspace as a whole.

#include <cstdio>
#include <string>
#include <vector>

#include "colmap_ext/workspace.h"
#include "colmap_ext/workspace_info.h"
#include "hairmvs/orientation_fields.h"
#include "src/cli/command_registry.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/option_parser.h"
#include "src/core/timer.h"
#include "src/orientation/orientation_maps.h"

namespace hairmvs {
namespace {

// What of each view is computed already: its cached orientation fields (up to date for
// `field_options` at the size of `max_image_size`, stale, or none) and its depth maps, so that
// a user (or a cluster's array) sees what is left to run.
void PrintOutputs(const Workspace& workspace, const OrientationFieldOptions& field_options,
                  int max_image_size) {
  std::printf("Outputs (orientation fields with these --OrientationField options at %s; "
              "depth and normal maps):\n",
              max_image_size > 0 ? ("max_image_size " + std::to_string(max_image_size)).c_str()
                                 : "full size");
  int up_to_date = 0, stale = 0, photometric = 0, geometric = 0;
  const std::vector<std::string>& names = workspace.ImageNames();
  for (const std::string& name : names) {
    const StereoCamera camera = workspace.ViewCamera(name).AtMaxImageSize(max_image_size);
    std::string why_not;
    const bool fields_ok =
        ReadCachedOrientationFields(
            workspace, name,
            OrientationFieldsProvenance(workspace, name, camera.width, camera.height,
                                        field_options),
            camera, field_options.num_levels, &why_not)
            .has_value();
    up_to_date += fields_ok;
    stale += !fields_ok && !why_not.empty();
    std::string maps;
    for (const char* type : {"photometric", "geometric"}) {
      if (ExistsFile(workspace.DepthMapPath(name, type)) &&
          ExistsFile(workspace.NormalMapPath(name, type))) {
        maps += std::string(maps.empty() ? "" : " ") + type;
        (type[0] == 'p' ? photometric : geometric) += 1;
      }
    }
    std::printf("  %s: fields %s; maps %s\n", name.c_str(),
                fields_ok ? "up to date"
                          : (why_not.empty() ? "none" : ("stale: " + why_not).c_str()),
                maps.empty() ? "none" : maps.c_str());
  }
  const int num_views = static_cast<int>(names.size());
  std::printf("  %d of %d views with up-to-date fields (%d stale); %d with .photometric and %d "
              "with .geometric maps\n",
              up_to_date, num_views, stale, photometric, geometric);
}

int RunWorkspaceInfo(int argc, char** argv) {
  std::string workspace_path;
  std::string mask_path;
  SourceViewOptions options;
  OrientationFieldOptions field_options;
  OptionParser parser("workspace_info",
                      "Lists the views, cameras, masks, source views (and why) and depth ranges "
                      "of a COLMAP dense workspace, and what of each view is computed already "
                      "(orientation fields up to date or stale, depth maps).");
  parser.Add("workspace_path", &workspace_path, "COLMAP dense workspace (image_undistorter)",
             true);
  parser.Add("mask_path", &mask_path,
             "folder of masks <image name>.png (default: <workspace>/masks if present)");
  parser.AddSection("SourceViews", &options);
  parser.AddSection("OrientationField", &field_options);
  int max_image_size = -1;
  parser.Add("max_image_size", &max_image_size,
             "check the orientation fields the stereo caches at this size (-1: full size, as "
             "orientation_fields makes them)");
  if (!parser.Parse(argc, argv)) return 0;
  std::string error;
  THROW_IF(!field_options.Check(&error), "invalid --OrientationField options: " << error);
  Timer timer;
  const WorkspaceInfo info = ComputeWorkspaceInfo(workspace_path, mask_path, options);
  std::printf("%s", info.Report().c_str());
  PrintOutputs(Workspace::Read(workspace_path, mask_path), field_options, max_image_size);
  std::printf("Total run time %.3f s (peak memory %.0f MiB)\n", timer.ElapsedSeconds(),
              PeakResidentMemoryMiB());
  return 0;
}

}  // namespace

HAIRMVS_REGISTER_COMMAND("workspace_info", RunWorkspaceInfo,
                         "views, cameras, masks, source views (and why), depth ranges of a "
                         "dense workspace, and what of each view is computed already");

}  // namespace hairmvs

