// hairmvs import_ground_truth / evaluate_depth / evaluate_data_term / evaluate_mesh: the
// ground truth of the synthetic data sets (shared/data/README.md) as a workspace, and the
// evaluators.

#include <cstdio>
#include <string>

#include "hairmvs/evaluation.h"
#include "src/cli/command_registry.h"
#include "src/core/logging.h"
#include "src/core/option_parser.h"
#include "src/core/timer.h"

namespace hairmvs {
namespace {

// The options of these commands are plain (--noise_m, --depth_type...), as in the README.
template <typename OptionsT>
void AddPlain(OptionParser* parser, OptionsT* options) {
  options->ForEachField(
      [parser](const char* field, auto* ptr, const char* help) { parser->Add(field, ptr, help); });
}

template <typename OptionsT>
void CheckOrThrow(const OptionsT& options) {
  std::string error;
  THROW_IF(!options.Check(&error), "invalid option: " << error);
}

int RunImportGroundTruth(int argc, char** argv) {
  std::string ground_truth_path, workspace_path, output_path;
  ImportGroundTruthOptions options;
  OptionParser parser(
      "import_ground_truth",
      "Writes a new dense workspace whose depth and normal maps are the ground truth (plus "
      "noise if asked): sparse/ copied, images/ and masks/ linked, stereo/*.cfg copied, "
      "stereo/depth_maps/<name>.geometric.bin and stereo/normal_maps/<name>.geometric.bin.");
  parser.Add("ground_truth_path", &ground_truth_path, "the data set's gt/ folder", true);
  parser.Add("workspace_path", &workspace_path, "the data set's dense workspace", true);
  parser.Add("output_path", &output_path, "the new workspace (not inside the data set)", true);
  AddPlain(&parser, &options);
  if (!parser.Parse(argc, argv)) return 0;
  CheckOrThrow(options);
  StageTimings timings;
  const ImportGroundTruthResult result =
      ImportGroundTruth(ground_truth_path, workspace_path, output_path, options, &timings);
  std::printf("%s\n%s", result.Report().c_str(), RunSummary(timings).c_str());
  return 0;
}

// evaluate_depth and evaluate_data_term: a workspace and the data set's truth, plain options,
// `evaluate(workspace_path, ground_truth_path, options)` whose result prints a per-view table.
template <typename OptionsT, typename EvaluateFn>
int RunWorkspaceEvaluation(int argc, char** argv, const char* name, const char* description,
                           const char* workspace_help, EvaluateFn evaluate) {
  std::string ground_truth_path, workspace_path;
  OptionsT options;
  OptionParser parser(name, description);
  parser.Add("workspace_path", &workspace_path, workspace_help, true);
  parser.Add("ground_truth_path", &ground_truth_path, "the data set's gt/ folder", true);
  AddPlain(&parser, &options);
  if (!parser.Parse(argc, argv)) return 0;
  CheckOrThrow(options);
  StageTimings timings;
  const auto result = evaluate(workspace_path, ground_truth_path, options, &timings);
  std::printf("%s%s", result.Table().c_str(), RunSummary(timings).c_str());
  return 0;
}

int RunEvaluateDepth(int argc, char** argv) {
  return RunWorkspaceEvaluation<DepthEvaluationOptions>(
      argc, argv, "evaluate_depth",
      "Compares a workspace's depth maps with the true ones on the hair pixels (label 2): "
      "absolute error (mean, median, fraction within 1/2/5 mm), completeness, 3D accuracy "
      "(pixels back-projected with the workspace's cameras, distance to the nearest true "
      "strand), the median signed error (> 0 behind the truth), and the median absolute and "
      "signed errors apart within --silhouette_band_px of the background and further in. "
      "Writes <output>/<name>.error.png, <output>/<name>.signed_error.png and "
      "<output>/depth_evaluation.json.",
      "dense workspace with depth maps",
      // A lambda: EvaluateDepthMaps is overloaded (also with a prebuilt strand index).
      [](const std::string& workspace, const std::string& truth,
         const DepthEvaluationOptions& options, StageTimings* timings) {
        return EvaluateDepthMaps(workspace, truth, options, timings);
      });
}

int RunEvaluateDataTerm(int argc, char** argv) {
  return RunWorkspaceEvaluation<DataTermEvaluationOptions>(
      argc, argv, "evaluate_data_term",
      "The data term alone, before the MRF: for each coarse pixel of the cost volumes that "
      "orientation_stereo --OrientationStereo.write_cost_volume 1 wrote, the cheapest label "
      "against the true depth (median of the hair pixels it covers): its error (median, "
      "within 1 label, 5 and 10 mm) and the fraction of labels cheaper than the true depth "
      "(median rank, 0 = the truth is the minimum). Writes "
      "<output>/data_term_evaluation.json.",
      "dense workspace with stereo/cost_volumes/", EvaluateDataTerm);
}

int RunEvaluateMesh(int argc, char** argv) {
  std::string mesh_path, ground_truth_path, workspace_path;
  MeshEvaluationOptions options;
  OptionParser parser(
      "evaluate_mesh",
      "Accuracy (mesh vertices and surface samples to the nearest true strand) and "
      "completeness (the visible true hair surface, i.e. hair pixels of the true depth maps "
      "back-projected with the true cameras, to the mesh surface: fraction within 2 and 5 mm), "
      "as the DTU benchmark measures them.");
  parser.Add("mesh", &mesh_path, "triangle mesh (PLY)", true);
  parser.Add("ground_truth_path", &ground_truth_path, "the data set's gt/ folder", true);
  parser.Add("workspace_path", &workspace_path,
             "optional: use its views for the visible surface and write the JSON into its "
             "stereo/evaluation/");
  AddPlain(&parser, &options);
  if (!parser.Parse(argc, argv)) return 0;
  CheckOrThrow(options);
  StageTimings timings;
  const MeshEvaluationResult result =
      EvaluateMesh(mesh_path, ground_truth_path, workspace_path, options, &timings);
  std::printf("%s%s", result.Report().c_str(), RunSummary(timings).c_str());
  return 0;
}

}  // namespace

HAIRMVS_REGISTER_COMMAND("import_ground_truth", RunImportGroundTruth,
                         "a workspace with the true depth/normal maps of a synthetic set");
HAIRMVS_REGISTER_COMMAND("evaluate_depth", RunEvaluateDepth,
                         "depth maps vs. the ground truth (per-pixel, completeness, 3D)");
HAIRMVS_REGISTER_COMMAND("evaluate_data_term", RunEvaluateDataTerm,
                         "the stereo's data term alone vs. the true depths (before the MRF)");
HAIRMVS_REGISTER_COMMAND("evaluate_mesh", RunEvaluateMesh,
                         "mesh accuracy and completeness vs. the true strands (DTU-style)");

}  // namespace hairmvs
