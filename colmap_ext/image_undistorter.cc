#include "colmap_ext/image_undistorter.h"

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "colmap_ext/reconstruction.h"
#include "colmap_ext/workspace.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace fs = std::filesystem;

namespace hairmvs {
namespace {

// Quotes a path for /bin/sh.
std::string ShellQuote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) {
    if (c == '\'') quoted += "'\\''";
    else quoted += c;
  }
  return quoted + "'";
}

// `colmap image_undistorter` with COLMAP's default options, the same for photos and masks.
// Returns the exit status (-1 when it did not exit normally).
int Undistort(const std::string& colmap_executable, const std::string& image_path,
              const std::string& input_path, const std::string& output_path,
              const std::string& extra_arguments) {
  const std::string command = "QT_QPA_PLATFORM=offscreen " + ShellQuote(colmap_executable) +
                              " image_undistorter --image_path " + ShellQuote(image_path) +
                              " --input_path " + ShellQuote(input_path) + " --output_path " +
                              ShellQuote(output_path) + " --output_type COLMAP" +
                              extra_arguments;
  std::fprintf(stderr, "[image_undistorter] %s\n", command.c_str());
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// A folder under the system's temporary directory, removed with everything in it at the end.
class ScratchDir {
 public:
  ScratchDir() {
    static std::atomic<int> counter{0};
    path_ = (fs::temp_directory_path() /
             ("hairmvs_masks_" + std::to_string(getpid()) + "_" + std::to_string(counter++)))
                .string();
    fs::remove_all(path_);
    CreateDirs(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::string& Path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace

void RunImageUndistorter(const std::string& colmap_executable, const std::string& image_path,
                         const std::string& input_path, const std::string& workspace_path) {
  RequireDir(image_path, "image folder (--image_path)");
  RequireDir(input_path, "sparse model folder (--input_path)");
  CreateDirs(workspace_path);
  const int status = Undistort(colmap_executable, image_path, input_path, workspace_path, "");
  THROW_IF(status != 0, "colmap image_undistorter failed (exit status "
                            << status << ") for --image_path " << image_path
                            << " --input_path " << input_path
                            << "; is COLMAP installed (apt-get install colmap)?");
}

MaskUndistortionResult UndistortMasks(const std::string& colmap_executable,
                                      const std::string& mask_path,
                                      const std::string& input_path,
                                      const std::string& workspace_path,
                                      int max_image_size) {
  RequireDir(mask_path, "mask folder of the photos");
  const Reconstruction photos = ReadReconstruction(input_path);
  // The workspace's names are the photos'; its masks are looked up in mask_path meanwhile.
  const Workspace workspace = Workspace::Read(workspace_path, mask_path);
  const ScratchDir scratch;
  const std::string binarised = JoinPaths(scratch.Path(), "masks");
  const std::string list_path = JoinPaths(scratch.Path(), "image_list.txt");
  MaskUndistortionResult result;
  std::vector<std::string> masked;  // the images that have a mask
  std::ofstream list(list_path);
  for (const std::string& name : workspace.ImageNames()) {
    const std::string path = workspace.MaskPath(name);
    if (path.empty()) {
      result.images_without_mask.push_back(name);
      continue;
    }
    const Camera& camera = photos.cameras.at(photos.ImageByName(name).camera_id);
    // At the photo's size, 1 where ReadMask keeps, so that the undistorter's interpolation
    // halves only at the rim. Staged as PNG under the photo's own name, whatever its
    // extension: colmap reads an image by its content.
    const std::string staged = JoinPaths(binarised, name);
    WriteImage(staged + ".png", ReadMask(path, static_cast<int>(camera.width),
                                         static_cast<int>(camera.height)));
    fs::rename(staged + ".png", staged);
    list << name << "\n";
    masked.push_back(name);
  }
  list.close();
  if (masked.empty()) return result;
  const std::string undistorted = JoinPaths(scratch.Path(), "undistorted");
  const int status = Undistort(colmap_executable, binarised, input_path, undistorted,
                               " --image_list_path " + ShellQuote(list_path) +
                                   " --max_image_size " + std::to_string(max_image_size));
  THROW_IF(status != 0, "colmap image_undistorter failed (exit status "
                            << status << ") on the masks of " << mask_path << " with --input_path "
                            << input_path);
  for (const std::string& name : masked) {
    const std::string path = JoinPaths(undistorted, "images", name);
    THROW_IF(!ExistsFile(path), "colmap image_undistorter wrote no " << path << " for the mask of "
                                                                     << name);
    FloatMap mask = ReadImageGray(path);
    const Camera& camera = workspace.Model().cameras.at(workspace.ImageByName(name).camera_id);
    THROW_IF(mask.Width() != static_cast<int>(camera.width) ||
                 mask.Height() != static_cast<int>(camera.height),
             "The undistorted mask of " << name << " (" << path << ") is not its image's "
                 << camera.width << " x " << camera.height << ": was " << workspace_path
                 << " undistorted from " << input_path
                 << " with other options (--max_image_size)?");
    for (float& value : mask.Data()) value = value > 0.5f ? 1.0f : 0.0f;  // 128 of 255 and up
    WriteImage(JoinPaths(workspace_path, "masks", name + ".png"), mask);
    ++result.num_masks;
  }
  return result;
}

}  // namespace hairmvs
