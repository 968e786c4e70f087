// hairmvs import_ground_truth: a dense workspace whose depth and normal maps are the truth.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <optional>
#include <random>
#include <sstream>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/reconstruction.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/evaluation.h"
#include "src/core/depth_geometry.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/progress.h"
#include "src/core/timer.h"
#include "src/evaluation/evaluation_util.h"
#include "src/evaluation/ground_truth.h"

namespace hairmvs {
namespace fs = std::filesystem;

namespace {

// images/ or masks/ of the output: a symlink to the workspace's folder, or a copy.
void LinkOrCopyFolder(const std::string& from, const std::string& to, bool copy) {
  if (!ExistsDir(from)) return;
  std::error_code ec;
  if (fs::is_symlink(to, ec)) fs::remove(to, ec);
  if (!copy) {
    THROW_IF(fs::exists(to), "Cannot link " << to << " to " << from
                                            << ": a folder of that name exists (use "
                                               "--copy_images 1 or remove it)");
    fs::create_directory_symlink(fs::absolute(from), to, ec);
    THROW_IF(ec, "Cannot create the symlink " << to << " -> " << from << ": " << ec.message());
    return;
  }
  for (const auto& entry : fs::recursive_directory_iterator(from)) {
    if (!entry.is_regular_file()) continue;
    const std::string relative = fs::relative(entry.path(), from).string();
    CopyFileAtomically(entry.path().string(), JoinPaths(to, relative));
  }
}

// The imported maps are the truth of the true cameras: the workspace's model with the true
// poses of the views `names` (gt/cameras.npz), from which a mapper's differ (synth_handheld:
// 0.24-0.43 degrees, 0.5-14 mm), so that the maps back-project onto the true strands in fusion
// and compare with the truth at their own pixels in evaluate_depth. Empty where the poses are
// the true ones already (the gantry sets): the model is copied as it is.
std::optional<Reconstruction> ModelWithTrueCameraPoses(const std::string& ground_truth_path,
                                                       const std::vector<std::string>& names,
                                                       Reconstruction model) {
  const std::string cameras_path = GroundTruthCamerasPath(ground_truth_path);
  if (!ExistsFile(cameras_path)) {
    LOG(WARNING) << "No " << cameras_path
                 << ": the workspace's poses are kept, and must be the true ones";
    return std::nullopt;
  }
  const GroundTruthCameras cameras = ReadGroundTruthCameras(ground_truth_path);
  double max_angle_rad = 0, max_shift_m = 0;
  for (auto& [id, image] : model.images) {
    if (std::find(names.begin(), names.end(), image.name) == names.end()) continue;
    const int i = cameras.Find(image.name);
    THROW_IF(i < 0, cameras_path << ": no camera named " << image.name
                                 << ", whose truth is imported");
    const Eigen::Quaterniond rotation(cameras.R[i]);
    max_angle_rad =
        std::max(max_angle_rad, rotation.angularDistance(image.cam_from_world_rotation));
    max_shift_m = std::max(max_shift_m, (cameras.Center(i) - image.ProjectionCenter()).norm());
    image.cam_from_world_rotation = rotation;
    image.cam_from_world_translation = cameras.t[i];
    const Eigen::Matrix3d K = model.cameras.at(image.camera_id).CalibrationMatrix();
    if ((K - cameras.K).norm() > 1e-6 * cameras.K(0, 0)) {
      LOG(WARNING) << "Image " << image.name << ": the workspace's intrinsics differ from "
                   << cameras_path << "'s; the true depths are written as they are";
    }
  }
  if (max_angle_rad < 1e-9 && max_shift_m < 1e-9) return std::nullopt;
  LOG(INFO) << "The true poses replace the workspace's for the imported views (which were off "
            << "by up to " << std::setprecision(3) << max_angle_rad * 180 / M_PI << " degrees and "
            << max_shift_m * 1e3 << " mm)";
  return model;
}

}  // namespace

bool ImportGroundTruthOptions::Check(std::string* error) const {
  // A metre of noise is no depth map (and an infinite one writes infinite depths).
  if (!(noise_m >= 0 && noise_m <= 1)) {
    *error = "--noise_m must be in [0, 1] (metres)";
    return false;
  }
  if (median_filter_px < 0 || median_filter_px > kMaxMedianFilterPx ||
      (median_filter_px > 0 && median_filter_px % 2 == 0)) {
    *error = "--median_filter_px must be 0 or odd, at most " +
             std::to_string(kMaxMedianFilterPx);
    return false;
  }
  return CheckImageNames(image_names, error);
}

std::string ImportGroundTruthResult::Report() const {
  std::ostringstream out;
  out << "Wrote " << num_views << " true depth and normal maps into " << output_path
      << " (kept " << std::fixed << std::setprecision(1) << 100.0 * kept_pixel_fraction
      << "% of the pixels)";
  return out.str();
}

ImportGroundTruthResult ImportGroundTruth(const std::string& ground_truth_path,
                                          const std::string& workspace_path,
                                          const std::string& output_path,
                                          const ImportGroundTruthOptions& options,
                                          StageTimings* timings) {
  std::string error;
  THROW_IF(!options.Check(&error), error);
  StageLaps laps(timings);
  THROW_IF(output_path.empty(), "Empty --output_path");
  RequireGroundTruthDir(ground_truth_path);  // before anything is written
  THROW_IF(IsSameOrInside(output_path, workspace_path),
           "--output_path " << output_path << " is inside the workspace " << workspace_path
                            << ": import_ground_truth writes a new workspace");
  RequireOutputApartFromInputs(output_path, "--output_path", ground_truth_path);
  THROW_IF(IsSameOrInside(workspace_path, output_path),
           "--output_path " << output_path << " contains the workspace " << workspace_path);
  const Workspace ws = Workspace::Read(workspace_path);
  const std::vector<std::string> names = ws.SelectImages(options.image_names);
  // Every view's truth, read and checked against its camera. All of them before anything is
  // written, so that a truth file cut short or of another data set leaves the output as it was:
  // not a workspace half made, nor an old one whose maps then mix two runs' settings.
  auto read_truth = [&](const std::string& name) {
    GroundTruthView view = ReadGroundTruthView(ground_truth_path, name);
    const Camera& camera = ws.CameraOf(name);
    THROW_IF(static_cast<int>(camera.width) != view.depth.Width() ||
                 static_cast<int>(camera.height) != view.depth.Height(),
             "Image " << name << ": the workspace camera is " << camera.width << " x "
                      << camera.height << " but the ground truth "
                      << GroundTruthViewPath(ground_truth_path, name) << " is "
                      << view.depth.Width() << " x " << view.depth.Height());
    return view;
  };
  for (const std::string& name : names) read_truth(name);
  const std::optional<Reconstruction> true_pose_model =
      ModelWithTrueCameraPoses(ground_truth_path, names, ws.Model());
  laps.Lap("check truth");

  // The frame of the new workspace: model, images, masks, configuration.
  CreateDirs(output_path);
  const std::string sparse_in = JoinPaths(workspace_path, "sparse");
  for (const auto& entry : fs::directory_iterator(sparse_in)) {
    if (entry.is_regular_file()) {
      CopyFileAtomically(entry.path().string(),
                         JoinPaths(output_path, "sparse", entry.path().filename().string()));
    }
  }
  LinkOrCopyFolder(JoinPaths(workspace_path, "images"), JoinPaths(output_path, "images"),
                   options.copy_images);
  LinkOrCopyFolder(JoinPaths(workspace_path, "masks"), JoinPaths(output_path, "masks"),
                   options.copy_images);
  for (const char* cfg : {"patch-match.cfg", "fusion.cfg"}) {
    const std::string from = JoinPaths(workspace_path, "stereo", cfg);
    if (ExistsFile(from)) CopyFileAtomically(from, JoinPaths(output_path, "stereo", cfg));
  }
  if (true_pose_model) {
    const std::string sparse_out = JoinPaths(output_path, "sparse");
    const bool binary = ExistsFile(JoinPaths(sparse_out, "images.bin"));
    WriteReconstruction(*true_pose_model, sparse_out,
                        binary ? ModelFormat::kBinary : ModelFormat::kText);
  }
  const Workspace out_ws = Workspace::Read(output_path);
  laps.Lap("workspace frame");

  ImportGroundTruthResult result;
  result.output_path = output_path;
  std::mt19937 rng(options.seed);
  // Drawn from only when noise_m > 0; the standard asks for a positive deviation regardless.
  std::normal_distribution<double> noise(0.0, options.noise_m > 0 ? options.noise_m : 1.0);
  size_t kept = 0, total = 0;
  std::vector<std::string> empty_views;  // written without a depth, with why
  Progress progress("import_ground_truth", static_cast<int>(names.size()));
  for (const std::string& name : names) {
    progress.Start(result.num_views, name);
    const GroundTruthView view = read_truth(name);
    const Camera& camera = ws.CameraOf(name);
    laps.Lap("read truth");
    FloatMap depth = view.depth;
    const auto keeps = [&](size_t p) {
      const uint8_t label = view.label[p];
      return label == kLabelHair || (!options.hair_only && label == kLabelSkin);
    };
    auto apply_labels = [&](FloatMap* map) {
      for (size_t p = 0; p < map->NumPixels(); ++p) {
        if (!keeps(p)) map->Data()[p] = 0.0f;
      }
    };
    if (options.median_filter_px > 1 && options.median_include_background) {
      depth = MedianFilterValidDepths(depth, options.median_filter_px, true);
    }
    apply_labels(&depth);
    if (options.median_filter_px > 1 && !options.median_include_background) {
      depth = MedianFilterValidDepths(depth, options.median_filter_px);
    }
    const size_t kept_before = kept;
    for (float& d : depth.Data()) {
      if (d > 0) {
        ++kept;
        if (options.noise_m > 0) d = static_cast<float>(std::max(1e-6, d + noise(rng)));
      }
    }
    if (kept == kept_before) {
      // Whether the truth has depths of the kept labels at all (else the median is not to
      // blame).
      bool has_kept_depths = false;
      for (size_t p = 0; p < view.depth.NumPixels() && !has_kept_depths; ++p) {
        has_kept_depths = view.depth.Data()[p] > 0 && keeps(p);
      }
      empty_views.push_back(
          has_kept_depths
              ? name + " (a median over windows mostly background: --median_include_background "
                       "0 takes the kept depths only)"
              : name + " (no true depth of the kept labels)");
    }
    total += depth.NumPixels();
    laps.Lap("labels, filter, noise");
    const Eigen::Matrix3d K = camera.CalibrationMatrix();
    WriteMat(out_ws.DepthMapPath(name, "geometric"), depth);
    WriteMat(out_ws.NormalMapPath(name, "geometric"), NormalMapFromDepthMap(depth, K));
    laps.Lap("normals, write");
    ++result.num_views;
  }
  progress.Finish();
  if (!empty_views.empty()) {
    LOG(WARNING) << empty_views.size() << " of the " << names.size()
                 << " depth maps written are empty: " << JoinStrings(empty_views, "; ");
  }
  result.kept_pixel_fraction = total > 0 ? static_cast<double>(kept) / total : 0.0;
  return result;
}

}  // namespace hairmvs
