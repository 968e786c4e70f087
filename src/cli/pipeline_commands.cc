// hairmvs pipeline: orientation fields, orientation stereo and template fusion in turn, on a
// COLMAP dense workspace; from a user's own photos, `colmap image_undistorter` first.

#include <cstdio>
#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "colmap_ext/image_undistorter.h"
#include "colmap_ext/source_views.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/evaluation.h"
#include "hairmvs/orientation_fields.h"
#include "hairmvs/orientation_stereo.h"
#include "hairmvs/template_fusion.h"
#include "src/cli/command_registry.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/option_parser.h"
#include "src/core/timer.h"
#include "src/evaluation/depth_evaluation.h"
#include "src/evaluation/ground_truth.h"
#include "src/opencl/opencl_options.h"

namespace hairmvs {
namespace {

bool HasStage(const std::vector<std::string>& stages, const std::string& stage) {
  for (const std::string& s : stages) {
    if (s == stage) return true;
  }
  return false;
}

int RunPipeline(int argc, char** argv) {
  std::string workspace_path;
  std::string image_path;
  std::string input_path;
  std::string photo_mask_path;
  std::string ground_truth_path;
  std::string colmap_executable = "colmap";
  std::vector<std::string> image_names;
  std::vector<std::string> stages = {"orientation", "stereo", "fusion"};
  bool write_png = true;
  OpenCLOptions opencl_options;
  OrientationFieldOptions orientation_options;
  OrientationStereoOptions stereo_options;
  SourceViewOptions source_options;
  TemplateFusionOptions fusion_options;

  OptionParser parser("pipeline",
                      "orientation fields, orientation stereo and template fusion on a COLMAP "
                      "dense workspace (runs colmap image_undistorter first when --image_path "
                      "and --input_path are given and the workspace does not exist yet)");
  parser.Add("workspace_path", &workspace_path, "COLMAP dense workspace", /*required=*/true);
  parser.Add("image_path", &image_path, "your photos (only to create the workspace)");
  parser.Add("input_path", &input_path,
             "sparse model from colmap mapper (only to create the workspace)");
  parser.Add("photo_mask_path", &photo_mask_path,
             "masks of your photos (<photo name>.png, 0 = excluded), undistorted with them into "
             "the new workspace's masks/ (only to create the workspace)");
  parser.Add("colmap_executable", &colmap_executable, "colmap binary for image_undistorter");
  parser.Add("image_names", &image_names,
             "reference views to process (comma-separated; empty = all). With a subset, the "
             "fusion stage is skipped: run `hairmvs template_fusion` once all views are done");
  parser.Add("stages", &stages, "stages to run, in order: orientation,stereo,fusion");
  parser.Add("ground_truth_path", &ground_truth_path,
             "a synthetic data set's gt/ folder: evaluate depth maps and mesh at the end");
  parser.Add("write_png", &write_png, "write orientation, depth and normal pictures");
  parser.AddSection("OpenCL", &opencl_options);
  parser.AddSection("OrientationField", &orientation_options,
                    OrientationStereoOptions::FieldOptionsSetHere());
  parser.AddSection("OrientationStereo", &stereo_options);
  parser.AddSection("SourceViews", &source_options);
  parser.AddSection("TemplateFusion", &fusion_options);
  if (!parser.Parse(argc, argv)) return 0;

  std::string error;
  THROW_IF(!orientation_options.Check(&error), "--OrientationField: " << error);
  THROW_IF(!stereo_options.Check(&error), "--OrientationStereo: " << error);
  THROW_IF(!fusion_options.Check(&error), "--TemplateFusion: " << error);
  THROW_IF(!source_options.Check(&error), "--SourceViews: " << error);
  THROW_IF(stages.empty(), "--stages: no stage given (orientation, stereo, fusion)");
  for (const std::string& stage : stages) {
    THROW_IF(stage != "orientation" && stage != "stereo" && stage != "fusion",
             "--stages: unknown stage '" << stage << "' (orientation, stereo, fusion)");
  }
  // Before colmap image_undistorter's minutes, not after them.
  THROW_IF(ExistsFile(workspace_path),
           "--workspace_path " << workspace_path << " is a file, not a folder");
  if (!ground_truth_path.empty()) {  // and before the stereo's, not after the fusion
    RequireDir(ground_truth_path, "ground truth folder (--ground_truth_path)");
  }

  Timer total;
  StageTimings timings;
  const std::string sparse_path = JoinPaths(workspace_path, "sparse");
  const bool workspace_exists = ExistsDir(sparse_path);
  if (workspace_exists && (!image_path.empty() || !input_path.empty())) {
    // The same command run again, to finish a stopped run: said, so that a workspace path
    // meant to be new is not taken for it unnoticed.
    const bool no_photos = !image_path.empty() && !ExistsDir(image_path);
    (no_photos ? LOG(WARNING) : LOG(INFO))
        << "The workspace " << workspace_path << " exists and is used as it is: --image_path "
        << "and --input_path, which only create it, are not read"
        << (no_photos ? " (and --image_path " + image_path + " does not exist)" : "");
  }
  if (!workspace_exists) {
    THROW_IF(image_path.empty() || input_path.empty(),
             "No COLMAP dense workspace at " << workspace_path << " (missing " << sparse_path
                                             << "); give --image_path and --input_path to "
                                                "create it with colmap image_undistorter");
    ScopedStageTimer timer(&timings, "image_undistorter");
    if (!photo_mask_path.empty()) {  // before the photos' undistortion, not after it
      RequireDir(photo_mask_path, "mask folder (--photo_mask_path)");
    }
    // The masks too are undistorted before the workspace is published: a workspace without
    // the masks asked for is not whole.
    MaskUndistortionResult masks;
    RunImageUndistorter(colmap_executable, image_path, input_path, workspace_path,
                        [&](const std::string& staged_workspace) {
                          if (photo_mask_path.empty()) return;
                          masks = UndistortMasks(colmap_executable, photo_mask_path, input_path,
                                                 staged_workspace);
                        });
    if (!photo_mask_path.empty()) {
      std::fprintf(stderr, "[pipeline] undistorted %d mask(s) of %s into %s\n", masks.num_masks,
                   photo_mask_path.c_str(), JoinPaths(workspace_path, "masks").c_str());
    }
  } else if (!photo_mask_path.empty()) {
    // The same command run again (to finish a stopped run): the masks it undistorted are there.
    const bool all_masked = ExistsDir(JoinPaths(workspace_path, "masks")) &&
                            Workspace::Read(workspace_path).ImagesWithoutMask().empty();
    THROW_IF(!all_masked,
             "--photo_mask_path " << photo_mask_path
                 << " holds masks of the photos, undistorted only when the workspace is "
                    "created; "
                 << workspace_path << " exists without a mask for every image: run `hairmvs "
                 << "undistort_masks --workspace_path " << workspace_path
                 << " --input_path <its sparse model> --photo_mask_path " << photo_mask_path
                 << "` (with --overwrite 1 to replace the masks it has), or put masks drawn on "
                 << "its images in " << workspace_path << "/masks");
    std::fprintf(stderr,
                 "[pipeline] %s exists with a mask for every image in %s/masks: those are used "
                 "(--photo_mask_path is undistorted only when the workspace is created)\n",
                 workspace_path.c_str(), workspace_path.c_str());
  }

  if (HasStage(stages, "stereo") || HasStage(stages, "fusion")) {
    // Before the orientation fields' minutes, not after them.
    Workspace::Read(workspace_path, stereo_options.mask_path).RequireUndistortedCameras();
  }

  const int num_stages = static_cast<int>(stages.size());
  int stage_index = 0;
  auto announce = [&](const std::string& stage) {
    std::fprintf(stderr, "[pipeline] stage %d/%d: %s (%.1f s elapsed)\n", ++stage_index,
                 num_stages, stage.c_str(), total.ElapsedSeconds());
  };

  if (HasStage(stages, "orientation")) {
    announce("orientation fields");
    OrientationFieldsRunOptions run_options;
    run_options.image_names = image_names;
    run_options.mask_path = stereo_options.mask_path;
    run_options.write_png = write_png;
    run_options.opencl_device = opencl_options.device;
    // The fields the stereo stage reads: at its size and with its levels, so that it reuses
    // them (and their pictures) rather than computing them again.
    run_options.max_image_size = stereo_options.max_image_size;
    const OrientationFieldsResult result = RunOrientationFields(
        workspace_path, stereo_options.FieldOptions(orientation_options), run_options, &timings);
    std::printf("%s\n", result.BriefReport().c_str());
  }
  if (HasStage(stages, "stereo")) {
    announce("orientation stereo");
    stereo_options.write_png = write_png;
    const OrientationStereoResult result = RunOrientationStereo(
        workspace_path, image_names, stereo_options, &timings, opencl_options.device,
        &source_options, &orientation_options);
    std::printf("%s\n", result.BriefReport().c_str());
  }
  // Whether meshed-hair.ply is this run's: the fusion stage runs on every view only.
  const bool fused = HasStage(stages, "fusion") && image_names.empty();
  if (HasStage(stages, "fusion")) {
    if (!fused) {
      std::fprintf(stderr,
                   "[pipeline] --image_names given: skipping fusion (run `hairmvs "
                   "template_fusion --workspace_path %s` once every view is done)\n",
                   workspace_path.c_str());
    } else {
      announce("template fusion");
      const TemplateFusionResult result =
          RunTemplateFusion(workspace_path, fusion_options, &timings);
      std::printf("%s\n", result.BriefReport().c_str());
    }
  }

  if (!ground_truth_path.empty()) {
    std::fprintf(stderr, "[pipeline] evaluation against %s\n", ground_truth_path.c_str());
    // What an earlier run left is evaluated too, but said to be so.
    if (!HasStage(stages, "stereo")) {
      std::fprintf(stderr,
                   "[pipeline] the stereo stage did not run in this call: evaluating the depth "
                   "maps an earlier run wrote\n");
    }
    DepthEvaluationOptions depth_options;
    depth_options.image_names = image_names;
    depth_options.depth_type = stereo_options.FinalMapType();  // what the stereo stage wrote
    const MeshEvaluationOptions mesh_options;
    // The true strands are indexed once for both evaluations (at the finer of the two spacings).
    std::unique_ptr<StrandDistance> strands;
    {
      ScopedStageTimer timer(&timings, "index true strands");
      strands = std::make_unique<StrandDistance>(
          ReadGroundTruthStrands(ground_truth_path),
          std::min(depth_options.strand_spacing_m, mesh_options.strand_spacing_m));
    }
    {
      ScopedStageTimer timer(&timings, "evaluate_depth");
      const DepthEvaluationResult depth =
          EvaluateDepthMaps(workspace_path, ground_truth_path, depth_options, *strands);
      std::printf("%s\n", depth.Table().c_str());
    }
    const std::string mesh_path = JoinPaths(workspace_path, "meshed-hair.ply");
    if (ExistsFile(mesh_path)) {
      if (!fused) {
        std::fprintf(stderr,
                     "[pipeline] the fusion stage did not run in this call: evaluating the "
                     "%s an earlier run wrote\n",
                     mesh_path.c_str());
      }
      ScopedStageTimer timer(&timings, "evaluate_mesh");
      const MeshEvaluationResult mesh =
          EvaluateMesh(mesh_path, ground_truth_path, workspace_path, mesh_options, *strands);
      std::printf("%s\n", mesh.Report().c_str());
    }
  }

  std::printf("%sWall time: %.1f s\n",
              RunSummary(timings, "hairmvs pipeline: time per stage").c_str(),
              total.ElapsedSeconds());
  // What this run wrote, to look at.
  const char* w = workspace_path.c_str();
  std::printf("Look at:\n");
  if (write_png && HasStage(stages, "orientation")) {
    std::printf("  %s/stereo/orientation_maps/*.png   orientation fields (hue = strand angle)\n",
                w);
  }
  if (write_png && HasStage(stages, "stereo")) {
    std::printf("  %s/stereo/depth_maps/*.png, normal_maps/*.png   depth and normal pictures\n", w);
  }
  if (HasStage(stages, "stereo")) {
    std::printf("  %s/stereo/depth_maps/*.%s.bin   for colmap stereo_fusion\n", w,
                stereo_options.FinalMapType().c_str());
  }
  if (!ground_truth_path.empty()) {
    std::printf("  %s/stereo/evaluation/*.png   error pictures\n", w);
  }
  if (fused) {
    std::printf("  %s/fused.ply, %s/meshed-hair.ply   the fused points and the hair surface "
                "(MeshLab; COLMAP's GUI shows fused.ply, with File > Import From, over "
                "sparse/)\n",
                w, w);
  }
  return 0;
}

}  // namespace

HAIRMVS_REGISTER_COMMAND("pipeline", RunPipeline,
                         "orientation fields + orientation stereo + template fusion on a "
                         "workspace (or from your photos via colmap image_undistorter)");

}  // namespace hairmvs
