#pragma once
// `colmap image_undistorter`, run for hairmvs: a dense workspace made from a user's photos,
// and the masks of those photos undistorted exactly as the photos were.

#include <functional>
#include <string>
#include <vector>

namespace hairmvs {

// Runs `colmap image_undistorter --output_type COLMAP` (COLMAP's defaults otherwise), so that
// `workspace_path` becomes the dense workspace of the photos in `image_path` and the model in
// `input_path`. The undistorter writes into a hidden folder beside `workspace_path`;
// `before_publishing` (if given) runs on that folder once it is whole (the pipeline undistorts
// the photos' masks there), and then its entries are moved into `workspace_path`, sparse/
// last. So a creation that fails, or that Ctrl-C stops, leaves no half workspace for the next
// run to take for a whole one (COLMAP creates sparse/ first and fills it last). Throws
// hairmvs::Error naming the folders and how colmap ended, or the entry of an existing
// `workspace_path` that the workspace would replace; refuses a `workspace_path` with a sparse/.
void RunImageUndistorter(
    const std::string& colmap_executable, const std::string& image_path,
    const std::string& input_path, const std::string& workspace_path,
    const std::function<void(const std::string& staged_workspace)>& before_publishing = {});

struct MaskUndistortionResult {
  int num_masks = 0;                             // written to workspace_path/masks
  std::vector<std::string> images_without_mask;  // photos that have no mask in mask_path
};

// Masks drawn on the photos (`mask_path`/<photo name>.png, 0 = excluded, COLMAP's naming) do
// not line up with the undistorted images, whose size and pixels the undistorter changed. This
// runs `colmap image_undistorter` again on the masks, binarised, in a folder under the system's
// temporary directory, and writes each result, thresholded at half (the undistorter
// interpolates), as `workspace_path`/masks/<image name>.png. Call it after RunImageUndistorter
// made the workspace, or on a workspace the user made with `colmap image_undistorter` from the
// same model, passing the --max_image_size it was given (-1: none; COLMAP's other undistorter
// options must be their defaults). Throws hairmvs::Error naming the mask for one that is empty
// or of another aspect ratio than its photo (ReadMask's rules), the folders if the undistorter
// fails, and the image whose undistorted mask is not its size (another model or options).
// Every mask is checked before any is written, so a failure leaves the workspace's masks/ as
// it was; a mask already in masks/ (drawn by hand, perhaps) is an error named before colmap
// runs, unless `overwrite`. A `mask_path` with no mask of any photo is an error.
MaskUndistortionResult UndistortMasks(const std::string& colmap_executable,
                                      const std::string& mask_path,
                                      const std::string& input_path,
                                      const std::string& workspace_path,
                                      int max_image_size = -1, bool overwrite = false);

}  // namespace hairmvs
