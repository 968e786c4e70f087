#pragma once
// `hairmvs workspace_info`: what a dense workspace holds and what the dense stages will do
// with it (views, cameras, masks, source views and why, depth ranges).

#include <string>
#include <vector>

#include "colmap_ext/source_views.h"

namespace hairmvs {

struct WorkspaceInfoViewRow {
  std::string name;
  int image_idx = 0;
  uint32_t image_id = 0;
  uint32_t camera_id = 0;
  int num_points2D = 0;
  int num_points3D = 0;  // observations with a 3D point
  std::string mask_path;  // "" = none
  double mask_keep_fraction = -1;  // share of pixels the mask keeps; -1 = no mask or unusable
  std::string mask_error;  // why the mask cannot be used (all zero, another aspect ratio)
  // Why the image cannot be used (unreadable, cut short, not its camera's size).
  std::string image_error;
  DepthRange depth_range;
};

struct WorkspaceInfo {
  std::string workspace_path;
  std::string mask_folder_note;
  int num_cameras = 0;
  int num_points3D = 0;
  std::vector<std::string> camera_lines;  // model, size, K (or params)
  std::vector<WorkspaceInfoViewRow> views;
  std::vector<SourceViewSelection> selections;
  int num_t_groups = 0;
  double seconds = 0;

  std::string Report() const;
};

// Throws hairmvs::Error for a workspace that cannot be read (see Workspace::Read).
WorkspaceInfo ComputeWorkspaceInfo(const std::string& workspace_path,
                                   const std::string& mask_path,
                                   const SourceViewOptions& options);

}  // namespace hairmvs
