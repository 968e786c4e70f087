// Commands on a COLMAP dense workspace as a whole.

#include <cstdio>
#include <string>
#include <vector>

#include "colmap_ext/image_undistorter.h"
#include "colmap_ext/workspace_info.h"
#include "hairmvs/orientation_fields.h"
#include "hairmvs/orientation_stereo.h"
#include "src/cli/command_registry.h"
#include "src/core/logging.h"
#include "src/core/option_parser.h"
#include "src/core/timer.h"

namespace hairmvs {
namespace {

// What of each view is computed already (WorkspaceOutputs), one line each and a count.
void PrintOutputs(const std::string& workspace_path, const OrientationStereoOptions& options,
                  const OrientationFieldOptions& field_options) {
  std::printf("Outputs (orientation fields with these --OrientationField options at %s; "
              "depth and normal maps):\n",
              options.max_image_size > 0
                  ? ("max_image_size " + std::to_string(options.max_image_size)).c_str()
                  : "full size");
  int up_to_date = 0, stale = 0, photometric = 0, geometric = 0;
  const std::vector<ViewOutputs> views = WorkspaceOutputs(workspace_path, options, field_options);
  for (const ViewOutputs& view : views) {
    std::string fields = "none";
    if (view.fields == ViewOutputs::Fields::kUpToDate) {
      fields = "up to date";
      ++up_to_date;
    } else if (view.fields == ViewOutputs::Fields::kStale) {
      fields = "stale: " + view.why_stale;
      ++stale;
    }
    photometric += view.photometric_maps;
    geometric += view.geometric_maps;
    std::string maps = view.photometric_maps ? "photometric" : "";
    if (view.geometric_maps) maps += maps.empty() ? "geometric" : " geometric";
    std::printf("  %s: fields %s; maps %s\n", view.name.c_str(), fields.c_str(),
                maps.empty() ? "none" : maps.c_str());
  }
  std::printf("  %d of %zu views with up-to-date fields (%d stale); %d with .photometric and %d "
              "with .geometric maps\n",
              up_to_date, views.size(), stale, photometric, geometric);
}

int RunWorkspaceInfo(int argc, char** argv) {
  std::string workspace_path;
  std::string mask_path;
  SourceViewOptions options;
  OrientationFieldOptions field_options;
  OptionParser parser("workspace_info",
                      "Lists the views, cameras, masks, source views (and why) and depth ranges "
                      "of a COLMAP dense workspace, and what of each view is computed already "
                      "(orientation fields up to date or stale, depth maps). Reads every image "
                      "and mask, and names those the stereo could not use.");
  parser.Add("workspace_path", &workspace_path, "COLMAP dense workspace (image_undistorter)",
             true);
  parser.Add("mask_path", &mask_path,
             "folder of masks <image name>.png (default: <workspace>/masks if present)");
  parser.AddSection("SourceViews", &options);
  parser.AddSection("OrientationField", &field_options,
                    OrientationStereoOptions::FieldOptionsSetHere());
  OrientationStereoOptions stereo_options;
  parser.Add("max_image_size", &stereo_options.max_image_size,
             "check the orientation fields the stereo caches at this size (-1: full size, as "
             "orientation_fields makes them)");
  if (!parser.Parse(argc, argv)) return 0;
  std::string error;
  THROW_IF(!field_options.Check(&error), "invalid --OrientationField options: " << error);
  // max_image_size is its one stereo option.
  THROW_IF(!stereo_options.Check(&error), "invalid --max_image_size: " << error);
  Timer timer;
  const WorkspaceInfo info = ComputeWorkspaceInfo(workspace_path, mask_path, options);
  stereo_options.mask_path = mask_path;  // the fields' provenance names the masks
  std::printf("%s", info.Report().c_str());
  PrintOutputs(workspace_path, stereo_options, field_options);
  std::printf("Total run time %.3f s (peak memory %.0f MiB)\n", timer.ElapsedSeconds(),
              PeakResidentMemoryMiB());
  return 0;
}

int RunUndistortMasks(int argc, char** argv) {
  std::string workspace_path;
  std::string input_path;
  std::string photo_mask_path;
  std::string colmap_executable = "colmap";
  int max_image_size = -1;
  bool overwrite = false;
  OptionParser parser("undistort_masks",
                      "Undistorts masks drawn on the photos into a dense workspace's masks/, "
                      "exactly as colmap image_undistorter undistorted the photos (it runs "
                      "again on the masks).");
  parser.Add("workspace_path", &workspace_path,
             "COLMAP dense workspace made by colmap image_undistorter", true);
  parser.Add("input_path", &input_path, "the sparse model it was undistorted from", true);
  parser.Add("photo_mask_path", &photo_mask_path,
             "masks of the photos, <photo name>.png (0 = excluded)", true);
  parser.Add("max_image_size", &max_image_size,
             "the --max_image_size image_undistorter was given (-1: none)");
  parser.Add("overwrite", &overwrite, "replace masks the workspace has already");
  parser.Add("colmap_executable", &colmap_executable, "colmap binary");
  if (!parser.Parse(argc, argv)) return 0;
  Timer timer;
  const MaskUndistortionResult result = UndistortMasks(
      colmap_executable, photo_mask_path, input_path, workspace_path, max_image_size, overwrite);
  std::printf("Undistorted %d mask(s) of %s into %s/masks (%zu image(s) without a mask) in "
              "%.1f s\n",
              result.num_masks, photo_mask_path.c_str(), workspace_path.c_str(),
              result.images_without_mask.size(), timer.ElapsedSeconds());
  return 0;
}

}  // namespace

HAIRMVS_REGISTER_COMMAND("undistort_masks", RunUndistortMasks,
                         "masks drawn on the photos, undistorted as the photos were into a "
                         "dense workspace's masks/");
HAIRMVS_REGISTER_COMMAND("workspace_info", RunWorkspaceInfo,
                         "views, cameras, masks, source views (and why), depth ranges of a "
                         "dense workspace, and what of each view is computed already");

}  // namespace hairmvs

