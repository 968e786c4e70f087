#include "colmap_ext/image_undistorter.h"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <utility>
#include <vector>

#include "colmap_ext/reconstruction.h"
#include "colmap_ext/workspace.h"
#include "src/core/depth_geometry.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace fs = std::filesystem;

namespace hairmvs {
namespace {

// Quotes an argument for /bin/sh: the command printed can be pasted into a shell.
std::string ShellQuote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) {
    if (c == '\'') quoted += "'\\''";
    else quoted += c;
  }
  return quoted + "'";
}

// Throws naming `executable` (a path, or a name looked up in PATH as execvp would) unless it is
// a file this process may execute: said before colmap is started, not as its exit status 127.
void RequireExecutable(const std::string& executable) {
  std::vector<std::string> candidates;
  if (executable.find('/') != std::string::npos) {
    candidates.push_back(executable);
  } else {
    const char* path = std::getenv("PATH");
    for (const std::string& dir : SplitString(path != nullptr ? path : "", ":")) {
      candidates.push_back(JoinPaths(dir.empty() ? "." : dir, executable));
    }
  }
  for (const std::string& candidate : candidates) {
    if (ExistsFile(candidate) && access(candidate.c_str(), X_OK) == 0) return;
  }
  HAIRMVS_THROW("Cannot run " << executable << ": "
                              << (executable.find('/') != std::string::npos
                                      ? (ExistsFile(executable) ? "not executable"
                                                                : "no such file")
                                      : "not found in PATH")
                              << "; install COLMAP (apt-get install colmap), or give its path "
                                 "with --colmap_executable");
}

// `colmap image_undistorter` with COLMAP's default options, the same for photos and masks, and
// `extra_arguments` after them. Returns waitpid()'s status (0: it exited with 0; -1 with errno
// if it could not be started).
//
// As system() would: this process ignores SIGINT and SIGQUIT while colmap runs, so a Ctrl-C at
// the terminal (which reaches the whole process group) stops colmap alone and is reported by
// its status. Unlike system(): colmap is started without a shell, and the kernel sends it
// SIGTERM if this process ends first (PR_SET_PDEATHSIG), so that a SIGTERM or SIGHUP to hairmvs
// alone (a scheduler's, or a closed terminal's) does not leave colmap writing into a scratch
// folder that the next run removes.
int Undistort(const std::string& colmap_executable, const std::string& image_path,
              const std::string& input_path, const std::string& output_path,
              const std::vector<std::string>& extra_arguments = {}) {
  RequireExecutable(colmap_executable);
  std::vector<std::string> arguments = {colmap_executable, "image_undistorter",
                                        "--image_path",    image_path,
                                        "--input_path",    input_path,
                                        "--output_path",   output_path,
                                        "--output_type",   "COLMAP"};
  arguments.insert(arguments.end(), extra_arguments.begin(), extra_arguments.end());
  std::string command = "QT_QPA_PLATFORM=offscreen";
  for (const std::string& argument : arguments) command += " " + ShellQuote(argument);
  std::fprintf(stderr, "[image_undistorter] %s\n", command.c_str());
  // Everything the child needs is allocated before fork(): after it, only async-signal-safe calls.
  std::vector<char*> argv;
  for (std::string& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);
  std::vector<std::string> environment = {"QT_QPA_PLATFORM=offscreen"};
  for (char** entry = environ; *entry != nullptr; ++entry) {
    if (std::strncmp(*entry, "QT_QPA_PLATFORM=", 16) != 0) environment.emplace_back(*entry);
  }
  std::vector<char*> envp;
  for (std::string& entry : environment) envp.push_back(entry.data());
  envp.push_back(nullptr);
  static constexpr char kExecFailed[] = "hairmvs: could not run colmap\n";

  struct sigaction ignore = {}, old_int = {}, old_quit = {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigaction(SIGINT, &ignore, &old_int);
  sigaction(SIGQUIT, &ignore, &old_quit);
  const pid_t parent = getpid();
  const pid_t child = fork();
  if (child == 0) {
    sigaction(SIGINT, &old_int, nullptr);
    sigaction(SIGQUIT, &old_quit, nullptr);
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(127);  // the parent ended before prctl
    execvpe(argv[0], argv.data(), envp.data());
    const ssize_t ignored = write(STDERR_FILENO, kExecFailed, sizeof(kExecFailed) - 1);
    (void)ignored;
    _exit(127);  // as a shell's "command not found"
  }
  int status = -1;
  if (child > 0) {
    while (waitpid(child, &status, 0) < 0) {
      if (errno != EINTR) {
        status = -1;
        break;
      }
    }
  }
  const int saved_errno = errno;
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGQUIT, &old_quit, nullptr);
  errno = saved_errno;
  return status;
}

// How a command that Undistort ran ended, for an error message.
std::string DescribeStatus(int status) {
  if (status == -1) return std::string("could not be started: ") + std::strerror(errno);
  if (WIFEXITED(status)) return "exit status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) {
    return "stopped by signal " + std::to_string(WTERMSIG(status)) + " (" +
           strsignal(WTERMSIG(status)) + ")";
  }
  return "status " + std::to_string(status);
}

// Moves what `from` holds into `to` (created if need be), sparse/ last: a workspace is whole
// once its sparse/ exists (the pipeline creates one where sparse/ is missing). Nothing is moved
// when an entry would replace one `to` has already.
void PublishWorkspace(const std::string& from, const std::string& to) {
  CreateDirs(to);
  std::vector<fs::path> entries;
  for (const fs::directory_entry& entry : fs::directory_iterator(from)) {
    const fs::path target = fs::path(to) / entry.path().filename();
    THROW_IF(fs::exists(target), "Cannot create the workspace "
                                     << to << ": it holds " << target.string()
                                     << " already; nothing was moved into it");
    entries.push_back(entry.path());
  }
  std::stable_partition(entries.begin(), entries.end(),
                        [](const fs::path& p) { return p.filename() != "sparse"; });
  for (const fs::path& entry : entries) {
    std::error_code ec;
    fs::rename(entry, fs::path(to) / entry.filename(), ec);
    THROW_IF(ec, "Cannot move " << entry.string() << " into the workspace " << to << ": "
                                << ec.message());
  }
}

}  // namespace

void RunImageUndistorter(const std::string& colmap_executable, const std::string& image_path,
                         const std::string& input_path, const std::string& workspace_path,
                         const std::function<void(const std::string&)>& before_publishing) {
  RequireDir(image_path, "image folder (--image_path)");
  RequireDir(input_path, "sparse model folder (--input_path)");
  THROW_IF(ExistsDir(JoinPaths(workspace_path, "sparse")),
           "Not creating the workspace " << workspace_path << ": it has a sparse/ model already");
  // The model read first: a folder that holds none (the mapper's sparse/ given for its
  // sparse/0, say) is named here, where colmap would abort with a stack trace.
  const Reconstruction model = ReadReconstruction(input_path);
  // Symlinks resolved: a workspace path that links to another file system is staged beside
  // where its entries will live, so that they are renamed there, not across file systems.
  fs::path target = fs::weakly_canonical(fs::absolute(workspace_path));
  if (!target.has_filename()) target = target.parent_path();  // "dense/"
  RequireExecutable(colmap_executable);  // before a folder is made for its output
  // The workspace's parent folders that this run makes, removed again (if still empty) when it
  // fails: a failed run leaves nothing behind.
  struct MadeFolders {
    std::vector<fs::path> paths;  // outermost first
    bool keep = false;
    ~MadeFolders() {
      std::error_code ec;
      for (auto it = paths.rbegin(); !keep && it != paths.rend(); ++it) fs::remove(*it, ec);
    }
  } made;
  for (fs::path p = target.parent_path(); !p.empty() && !fs::exists(p); p = p.parent_path()) {
    made.paths.insert(made.paths.begin(), p);
  }
  CreateDirs(target.parent_path().string());
  // Beside the workspace (the same file system, so that its entries are renamed, not copied),
  // hidden, and removed if anything fails or colmap is stopped.
  const ScratchDir staging(target.parent_path().string(),
                           "." + target.filename().string() + ".undistorting");
  const int status = Undistort(colmap_executable, image_path, input_path, staging.Path());
  // (colmap itself was found and started: RequireExecutable; its own messages say why it
  // failed.)
  THROW_IF(status != 0, "colmap image_undistorter " << DescribeStatus(status)
                            << " for --image_path " << image_path << " --input_path "
                            << input_path << " (see colmap's messages above). "
                            << "Nothing was written to " << workspace_path);
  // colmap image_undistorter passes over a photo it cannot read ("Cannot read image") and
  // still exits 0; a workspace without it would fail every later command.
  for (const auto& [id, image] : model.images) {
    THROW_IF(!ExistsFile(JoinPaths(staging.Path(), "images", image.name)),
             "colmap image_undistorter wrote no image for "
                 << JoinPaths(image_path, image.name) << ", which the model " << input_path
                 << " lists: is it missing or unreadable? Nothing was written to "
                 << workspace_path);
  }
  if (before_publishing) before_publishing(staging.Path());
  PublishWorkspace(staging.Path(), workspace_path);
  made.keep = true;
}

MaskUndistortionResult UndistortMasks(const std::string& colmap_executable,
                                      const std::string& mask_path,
                                      const std::string& input_path,
                                      const std::string& workspace_path,
                                      int max_image_size, bool overwrite) {
  // As image_undistorter takes it; colmap aborts on 0 (and takes a negative one as none).
  THROW_IF(!IsValidMaxImageSize(max_image_size),
           "--max_image_size " << max_image_size
                               << " must be > 0 or -1 (none), as given to image_undistorter");
  RequireDir(mask_path, "mask folder of the photos");
  const Reconstruction photos = ReadReconstruction(input_path);
  // The workspace's names are the photos'; its masks are looked up in mask_path meanwhile.
  const Workspace workspace =
      Workspace::Read(workspace_path, mask_path, Workspace::MasksOf::kPhotos);
  const ScratchDir scratch(fs::temp_directory_path().string(), "hairmvs_masks_");
  const std::string binarised = JoinPaths(scratch.Path(), "masks");
  const std::string list_path = JoinPaths(scratch.Path(), "image_list.txt");
  // Where an image's undistorted mask goes.
  auto workspace_mask = [&](const std::string& name) {
    return JoinPaths(workspace_path, "masks", name + ".png");
  };
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
  // (A mask folder that matches no photo, a wrong folder or naming, was refused by
  // Workspace::Read above.)
  // Masks already there may be drawn by hand: replaced only when asked, and named before
  // colmap runs.
  if (!overwrite) {
    for (const std::string& name : masked) {
      THROW_IF(ExistsFile(workspace_mask(name)),
               "The workspace has a mask already: " << workspace_mask(name)
                   << " (undistort_masks replaces masks only with --overwrite 1)");
    }
  }
  const std::string undistorted = JoinPaths(scratch.Path(), "undistorted");
  const int status = Undistort(colmap_executable, binarised, input_path, undistorted,
                               {"--image_list_path", list_path, "--max_image_size",
                                std::to_string(max_image_size)});
  THROW_IF(status != 0, "colmap image_undistorter " << DescribeStatus(status)
                                                    << " on the masks of " << mask_path
                                                    << " with --input_path " << input_path);
  // Every mask is read, checked and thresholded before any is written, so that a mask that
  // fails leaves the workspace's masks as they were.
  const std::string thresholded = JoinPaths(scratch.Path(), "thresholded");
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
    WriteImage(JoinPaths(thresholded, name + ".png"), mask);
  }
  // One unit: a copy that fails (a full disk) leaves masks/ as it was, not half replaced.
  std::vector<std::pair<std::string, std::string>> copies;
  for (const std::string& name : masked) {
    copies.emplace_back(JoinPaths(thresholded, name + ".png"), workspace_mask(name));
  }
  CopyFilesAtomically(copies);
  result.num_masks = static_cast<int>(copies.size());
  return result;
}

}  // namespace hairmvs
