// hairmvs evaluate_mesh: accuracy and completeness of a mesh against the true hair, as the
// DTU benchmark (Aanaes et al. 2016) measures them: accuracy = distance from the reconstruction
// to the truth, completeness = distance from the (visible) truth to the reconstruction.

#include <nlohmann/json.hpp>

#include <Eigen/Core>
#include <algorithm>
#include <iomanip>
#include <random>
#include <sstream>

#include "colmap_ext/ply.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/evaluation.h"
#include "src/core/depth_geometry.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/progress.h"
#include "src/core/timer.h"
#include "src/evaluation/depth_evaluation.h"
#include "src/evaluation/evaluation_util.h"
#include "src/evaluation/ground_truth.h"
#include "src/evaluation/mesh_distance.h"

namespace hairmvs {
namespace {

nlohmann::json ToJson(const DistanceStats& s) {
  return {{"count", s.count}, {"mean_mm", s.mean_mm}, {"median_mm", s.median_mm},
          {"p90_mm", s.p90_mm}};
}

std::string Line(const std::string& what, const DistanceStats& s) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << what << ": mean " << s.mean_mm << " mm, median "
      << s.median_mm << " mm, 90% " << s.p90_mm << " mm (" << s.count << " points)\n";
  return out.str();
}

}  // namespace

bool MeshEvaluationOptions::Check(std::string* error) const {
  if (!(face_sample_spacing_m >= 0)) {
    *error = "--face_sample_spacing_m must be >= 0";
    return false;
  }
  if (!(surface_sample_spacing_m > 0)) {
    *error = "--surface_sample_spacing_m must be > 0";
    return false;
  }
  if (max_ground_truth_points <= 0) {
    *error = "--max_ground_truth_points must be > 0";
    return false;
  }
  if (!(strand_spacing_m > 0)) {
    *error = "--strand_spacing_m must be > 0";
    return false;
  }
  if (!output_json.empty() && ExistsDir(output_json)) {  // found before the work, not after
    *error = "--output_json " + output_json + " is a folder; give the JSON file's path";
    return false;
  }
  return true;
}

std::string MeshEvaluationResult::Report() const {
  std::ostringstream out;
  out << "Mesh: " << num_vertices << " vertices, " << num_faces << " faces\n";
  out << Line("Accuracy (vertices to true strands)", accuracy_vertices);
  if (accuracy_surface.count > 0) {
    out << Line("Accuracy (surface samples to true strands)", accuracy_surface);
  }
  out << Line("Completeness distance (visible true hair to mesh)", completeness_distance);
  out << std::fixed << std::setprecision(1) << "Completeness: " << 100 * completeness_2mm
      << "% within 2 mm, " << 100 * completeness_5mm << "% within 5 mm\n";
  if (!json_path.empty()) out << "Summary: " << json_path << "\n";
  return out.str();
}

namespace {

// Checks the options and reads the mesh (a surface), timed as its own stage.
TriangleMesh ReadMeshToEvaluate(const std::string& mesh_path, const MeshEvaluationOptions& options,
                                StageTimings* timings) {
  std::string error;
  THROW_IF(!options.Check(&error), error);
  StageLaps laps(timings);
  TriangleMesh mesh = ReadMeshPly(mesh_path);
  THROW_IF(mesh.vertices.empty() || mesh.faces.empty(),
           mesh_path << ": the mesh has " << mesh.vertices.size() << " vertices and "
                     << mesh.faces.size() << " faces; a surface is needed");
  laps.Lap("read mesh");
  return mesh;
}

MeshEvaluationResult EvaluateReadMesh(const TriangleMesh& mesh, const std::string& mesh_path,
                                      const std::string& ground_truth_path,
                                      const std::string& workspace_path,
                                      const MeshEvaluationOptions& options,
                                      const StrandDistance& strand_distance,
                                      StageTimings* timings) {
  StageLaps laps(timings);
  MeshEvaluationResult result;
  result.num_vertices = static_cast<long>(mesh.vertices.size());
  result.num_faces = static_cast<long>(mesh.faces.size());
  std::mt19937 rng(options.seed);

  Progress progress("evaluate_mesh", 3);
  progress.Start(0, "accuracy: the mesh to the true strands");
  std::vector<Eigen::Vector3d> vertices;
  for (const Eigen::Vector3f& v : mesh.vertices) vertices.push_back(v.cast<double>());
  result.accuracy_vertices = SummarizeDistances(strand_distance.Distances(vertices));
  if (options.face_sample_spacing_m > 0) {
    const std::vector<Eigen::Vector3d> samples =
        SampleMeshSurface(mesh, options.face_sample_spacing_m, &rng, mesh_path);
    result.accuracy_surface = SummarizeDistances(strand_distance.Distances(samples));
  }

  laps.Lap("accuracy");
  // Completeness: the visible true hair surface (hair pixels of the true depth maps,
  // back-projected with the true cameras) to the mesh surface.
  const GroundTruthCameras cameras = ReadGroundTruthCameras(ground_truth_path);
  std::vector<std::string> names = cameras.names;
  if (!workspace_path.empty()) names = Workspace::Read(workspace_path).ImageNames();
  progress.Start(1, "the visible true hair of " + std::to_string(names.size()) + " views");
  std::vector<Eigen::Vector3f> surface;
  for (const std::string& name : names) {
    const GroundTruthView view = ReadGroundTruthView(ground_truth_path, name);
    const StereoCamera camera =
        TrueCamera(cameras, ground_truth_path, name, view.depth.Width(), view.depth.Height());
    for (int r = 0; r < view.depth.Height(); ++r) {
      for (int c = 0; c < view.depth.Width(); ++c) {
        const float d = view.depth.At(r, c);
        if (view.label[static_cast<size_t>(r) * view.depth.Width() + c] != kLabelHair || !(d > 0)) {
          continue;
        }
        surface.push_back(camera.BackProject(c, r, d).cast<float>());
      }
    }
  }
  THROW_IF(surface.empty(), ground_truth_path << ": no hair pixels in the true depth maps");
  if (surface.size() > static_cast<size_t>(options.max_ground_truth_points)) {
    std::shuffle(surface.begin(), surface.end(), rng);
    surface.resize(options.max_ground_truth_points);
  }
  laps.Lap("true visible surface");
  progress.Start(2, "completeness: " + std::to_string(surface.size()) +
                        " true surface points to the mesh");
  std::vector<Eigen::Vector3d> queries;
  for (const Eigen::Vector3f& p : surface) queries.push_back(p.cast<double>());
  const TriangleMeshDistance mesh_distance(mesh, options.surface_sample_spacing_m, mesh_path);
  const std::vector<double> completeness = mesh_distance.Distances(queries);
  long within2 = 0, within5 = 0;
  for (double d : completeness) {
    within2 += d <= 2e-3;
    within5 += d <= 5e-3;
  }
  result.completeness_2mm = static_cast<double>(within2) / completeness.size();
  result.completeness_5mm = static_cast<double>(within5) / completeness.size();
  result.completeness_distance = SummarizeDistances(completeness);
  progress.Finish();

  result.json_path = options.output_json;
  if (result.json_path.empty()) {
    result.json_path = workspace_path.empty()
                           ? mesh_path + ".evaluation.json"
                           : JoinPaths(workspace_path, "stereo", "evaluation",
                                       "mesh_evaluation.json");
  }
  nlohmann::json json;
  json["mesh"] = mesh_path;
  json["ground_truth_path"] = ground_truth_path;
  json["num_vertices"] = result.num_vertices;
  json["num_faces"] = result.num_faces;
  json["accuracy_vertices"] = ToJson(result.accuracy_vertices);
  json["accuracy_surface"] = ToJson(result.accuracy_surface);
  json["face_sample_spacing_m"] = options.face_sample_spacing_m;
  json["completeness_distance"] = ToJson(result.completeness_distance);
  json["completeness_2mm"] = result.completeness_2mm;
  json["completeness_5mm"] = result.completeness_5mm;
  json["num_views"] = names.size();
  WriteJsonSummary(result.json_path, json);
  laps.Lap("completeness");
  return result;
}

}  // namespace

MeshEvaluationResult EvaluateMesh(const std::string& mesh_path,
                                  const std::string& ground_truth_path,
                                  const std::string& workspace_path,
                                  const MeshEvaluationOptions& options,
                                  StageTimings* timings) {
  RequireOutputApartFromInputs(options.output_json, "--output_json", ground_truth_path, mesh_path);
  // The mesh first: a missing or malformed one is named at once, not after the strands' index
  // (seconds to minutes) is built.
  const TriangleMesh mesh = ReadMeshToEvaluate(mesh_path, options, timings);
  StageLaps laps(timings);
  Timer timer;
  const GroundTruthStrands strands = ReadGroundTruthStrands(ground_truth_path);
  const StrandDistance strand_distance(strands, options.strand_spacing_m);
  LOG(INFO) << "True strands indexed: " << strand_distance.NumSamples() << " samples ("
            << timer.ElapsedSeconds() << " s)";
  laps.Lap("true strands");
  return EvaluateReadMesh(mesh, mesh_path, ground_truth_path, workspace_path, options,
                          strand_distance, timings);
}

MeshEvaluationResult EvaluateMesh(const std::string& mesh_path,
                                  const std::string& ground_truth_path,
                                  const std::string& workspace_path,
                                  const MeshEvaluationOptions& options,
                                  const StrandDistance& strand_distance,
                                  StageTimings* timings) {
  RequireOutputApartFromInputs(options.output_json, "--output_json", ground_truth_path, mesh_path);
  return EvaluateReadMesh(ReadMeshToEvaluate(mesh_path, options, timings), mesh_path,
                          ground_truth_path, workspace_path, options, strand_distance, timings);
}

}  // namespace hairmvs
