#include "hairmvs/template_fusion.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/ply.h"
#include "colmap_ext/source_views.h"
#include "colmap_ext/workspace.h"
#include "src/core/depth_geometry.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/progress.h"
#include "src/fusion/fusion_points.h"
#include "src/fusion/poisson_template.h"
#include "src/fusion/template_fusion_core.h"

namespace hairmvs {
namespace {

#define CHECK_OPTION(cond, message) \
  do {                              \
    if (!(cond)) {                  \
      *error = message;             \
      return false;                 \
    }                               \
  } while (0)

// A map resampled (nearest) to width x height: images may be larger than depth maps written
// with a maximum image size.
FloatMap ResizeNearest(const FloatMap& map, int width, int height) {
  if (map.Width() == width && map.Height() == height) return map;
  FloatMap out(width, height, map.Channels());
  for (int c = 0; c < map.Channels(); ++c) {
    for (int row = 0; row < height; ++row) {
      const int r =
          std::min(map.Height() - 1, static_cast<int>((row + 0.5) * map.Height() / height));
      for (int col = 0; col < width; ++col) {
        const int k =
            std::min(map.Width() - 1, static_cast<int>((col + 0.5) * map.Width() / width));
        out.At(row, col, c) = map.At(r, k, c);
      }
    }
  }
  return out;
}

TriangleMesh ToTriangleMesh(const FusionMesh& mesh) {
  TriangleMesh out;
  for (const Eigen::Vector3d& v : mesh.vertices) out.vertices.push_back(v.cast<float>());
  for (const Eigen::Vector3d& n : mesh.normals) out.normals.push_back(n.cast<float>());
  out.colors = mesh.colors;
  out.faces = mesh.faces;
  return out;
}

}  // namespace

bool TemplateFusionOptions::Check(std::string* error) const {
  CHECK_OPTION(input_type == "auto" || input_type == "geometric" || input_type == "photometric",
               "TemplateFusion.input_type must be auto, geometric or photometric");
  CHECK_OPTION(point_stride_px >= 1, "TemplateFusion.point_stride_px must be >= 1");
  // Upper bounds keep an absurd value from a crash or hours of work after the maps are read.
  CHECK_OPTION(fused_voxel_size_px > 0 && fused_voxel_size_px <= 100,
               "TemplateFusion.fused_voxel_size_px must be in (0, 100]");
  CHECK_OPTION(visibility_depth_tolerance > 0 && visibility_depth_tolerance < 1,
               "TemplateFusion.visibility_depth_tolerance must be in (0, 1)");
  CHECK_OPTION(min_num_visible_views >= 1, "TemplateFusion.min_num_visible_views must be >= 1");
  CHECK_OPTION(poisson_depth >= 3 && poisson_depth <= 12,
               "TemplateFusion.poisson_depth must be in [3, 12]");
  CHECK_OPTION(poisson_scale >= 1 && poisson_scale <= 4,
               "TemplateFusion.poisson_scale must be in [1, 4]");
  CHECK_OPTION(poisson_sample_cells > 0, "TemplateFusion.poisson_sample_cells must be > 0");
  CHECK_OPTION(trim_distance_cells > 0, "TemplateFusion.trim_distance_cells must be > 0");
  CHECK_OPTION(trim_min_sample_spacings >= 0,
               "TemplateFusion.trim_min_sample_spacings must be >= 0");
  CHECK_OPTION(min_component_fraction >= 0 && min_component_fraction <= 1,
               "TemplateFusion.min_component_fraction must be in [0, 1]");
  // The subdivision stops at max_mesh_vertices, whatever the edge length asks for; 2e7
  // vertices take a few GiB with their fit terms.
  CHECK_OPTION(target_edge_length_px >= 0.1,
               "TemplateFusion.target_edge_length_px must be >= 0.1");
  CHECK_OPTION(max_mesh_vertices >= 100 && max_mesh_vertices <= 20000000,
               "TemplateFusion.max_mesh_vertices must be in [100, 2e7]");
  // The graph's nodes grow with 1 / spacing^2: a quarter cell is already 100 times the default's.
  CHECK_OPTION(node_spacing_cells >= 0.25 && node_spacing_cells <= 1000,
               "TemplateFusion.node_spacing_cells must be in [0.25, 1000]");
  CHECK_OPTION(num_node_neighbors >= 1 && num_node_neighbors <= 8,
               "TemplateFusion.num_node_neighbors must be in [1, 8]");
  CHECK_OPTION(num_rounds >= 0 && num_rounds <= 100,
               "TemplateFusion.num_rounds must be in [0, 100]");
  CHECK_OPTION(fit_weight > 0, "TemplateFusion.fit_weight must be > 0");
  CHECK_OPTION(rigidity_weight >= 0, "TemplateFusion.rigidity_weight must be >= 0");
  CHECK_OPTION(smoothness_weight >= 0, "TemplateFusion.smoothness_weight must be >= 0");
  CHECK_OPTION(regularization_decay > 0 && regularization_decay <= 1,
               "TemplateFusion.regularization_decay must be in (0, 1]");
  CHECK_OPTION(max_fit_distance_cells > 0, "TemplateFusion.max_fit_distance_cells must be > 0");
  CHECK_OPTION(max_fit_vertices >= 1 && max_fit_vertices <= 20000000,
               "TemplateFusion.max_fit_vertices must be in [1, 2e7]");
  CHECK_OPTION(max_solver_iterations >= 1 && max_solver_iterations <= 1000,
               "TemplateFusion.max_solver_iterations must be in [1, 1000]");
  CHECK_OPTION(max_detail_offset_cells >= 0,
               "TemplateFusion.max_detail_offset_cells must be >= 0");
  CHECK_OPTION(detail_smoothness_weight >= 0 && detail_smoothness_weight <= 1e6,
               "TemplateFusion.detail_smoothness_weight must be in [0, 1e6]");
  CHECK_OPTION(max_detail_view_angle_deg > 0 && max_detail_view_angle_deg < 90,
               "TemplateFusion.max_detail_view_angle_deg must be in (0, 90)");
  CHECK_OPTION(num_threads >= 1 && num_threads <= 256,
               "TemplateFusion.num_threads must be in [1, 256]");
  return true;
}

std::string TemplateFusionResult::BriefReport() const {
  std::ostringstream out;
  out << "template_fusion: " << num_views << " depth maps, " << num_input_points
      << " pixels -> " << num_fused_points << " fused points, " << num_poisson_points
      << " Poisson samples (octree cell " << octree_cell_m * 1e3 << " mm)\n"
      << "  coarse template: " << coarse_num_vertices << " vertices, " << coarse_num_faces
      << " faces\n"
      << "  final mesh: " << final_num_vertices << " vertices, " << final_num_faces
      << " faces, " << num_components << " component(s), Euler characteristic "
      << euler_characteristic << ", median detail offset " << median_detail_offset_m * 1e3
      << " mm\n"
      << "  " << fused_path << "\n  " << mesh_path << "\n"
      << "  " << seconds << " s, peak memory " << peak_memory_mib << " MiB";
  return out.str();
}

FusionOutput FuseViews(const std::vector<FusionView>& views, const TemplateFusionOptions& options,
                       StageTimings* timings) {
  std::string error;
  THROW_IF(!options.Check(&error), error);
  FusionOutput out;
  FusionPoints samples;
  {
    ScopedStageTimer timer(timings, "points");
    out.footprint_m = MedianPixelFootprint(views);
    THROW_IF(!(out.footprint_m > 0), "template_fusion: the depth maps have no valid pixel");
    const FusionPoints points = ExtractFusionPoints(views, options, &out.num_input_points);
    THROW_IF(points.Size() < 100, "template_fusion: only " << points.Size()
                                      << " points are seen by at least "
                                      << options.min_num_visible_views << " depth maps (of the "
                                      << views.size() << " fused, a point every "
                                      << options.point_stride_px << " px: point_stride_px)");
    out.fused = VoxelMergePoints(points, options.fused_voxel_size_px * out.footprint_m);
    // Voxels whose normals cancel are dropped: maps that face every way at once leave nothing.
    THROW_IF(out.fused.Size() < 2, "template_fusion: only "
                                       << out.fused.Size() << " of " << points.Size()
                                       << " points are left after merging voxels whose normals "
                                          "agree; the depth maps' normals cancel out");
    out.cell_m = PoissonCellSize(out.fused, options);
    THROW_IF(!(out.cell_m > 0), "template_fusion: the " << out.fused.Size()
                                                        << " fused points lie at one place; "
                                                           "there is no surface to mesh");
    samples = VoxelMergePoints(out.fused, options.poisson_sample_cells * out.cell_m);
    out.num_poisson_points = static_cast<int>(samples.Size());
    std::fprintf(stderr,
                 "[template_fusion] points: %d pixels -> %zu fused points -> %zu Poisson samples "
                 "(octree cell %.3g m)\n",
                 out.num_input_points, out.fused.Size(), samples.Size(), out.cell_m);
  }
  {
    ScopedStageTimer timer(timings, "coarse template (Poisson)");
    out.coarse = PoissonTemplate(
        samples, options, out.cell_m,
        std::max(options.fused_voxel_size_px * out.footprint_m,
                 options.poisson_sample_cells * out.cell_m));
    THROW_IF(out.coarse.faces.empty(), "template_fusion: Poisson gave an empty template");
    std::fprintf(stderr, "[template_fusion] coarse template: %zu vertices, %zu faces\n",
                 out.coarse.vertices.size(), out.coarse.faces.size());
  }
  {
    ScopedStageTimer timer(timings, "refined template (deformation graph)");
    // Subdivide so that the vertices are dense enough to carry the detail later.
    const double target_edge = options.target_edge_length_px * out.footprint_m;
    int iterations = 0;
    double edge = out.coarse.MeanEdgeLength();
    size_t num_vertices = out.coarse.vertices.size();
    while (edge > target_edge &&
           num_vertices * 4 <= static_cast<size_t>(options.max_mesh_vertices)) {
      edge *= 0.5;
      num_vertices *= 4;
      ++iterations;
    }
    out.refined = SubdivideLoop(out.coarse, iterations);
    out.registration = RefineTemplate(views, options, out.cell_m, &out.refined);
  }
  {
    ScopedStageTimer timer(timings, "detail");
    out.final_mesh = out.refined;
    out.detail = TransferDetail(views, options, out.cell_m, &out.final_mesh);
    ColorizeMesh(views, options, &out.final_mesh);
    std::fprintf(stderr,
                 "[template_fusion] detail: %d of %zu vertices moved, median |offset| %.3g m\n",
                 out.detail.num_vertices_with_detail, out.final_mesh.vertices.size(),
                 out.detail.median_abs_offset_m);
  }
  return out;
}

TemplateFusionResult RunTemplateFusion(const std::string& workspace_path,
                                       const TemplateFusionOptions& options,
                                       StageTimings* timings) {
  std::string error;
  THROW_IF(!options.Check(&error), error);
  Timer total_timer;
  StageTimings local_timings;
  if (timings == nullptr) timings = &local_timings;

  std::vector<FusionView> views;
  std::vector<uint32_t> image_idx_of_view;
  {
    ScopedStageTimer timer(timings, "read depth maps");
    const Workspace workspace = Workspace::Read(workspace_path);
    // fused.ply and meshed-hair.ply go there, after minutes of work. (After the workspace is
    // read: a mistyped path is refused as no workspace, not made.)
    RequireWritableDir(workspace_path, "workspace");
    const std::vector<std::string>& names = workspace.ImageNames();
    // As colmap stereo_fusion: stereo/fusion.cfg, where it exists, says which views are fused
    // (their index in .vis stays the model's).
    std::set<std::string> listed(names.begin(), names.end());
    const std::string fusion_cfg = JoinPaths(workspace.StereoPath(), "fusion.cfg");
    if (Exists(fusion_cfg)) {  // a folder there too: ReadFusionConfig says it is no file
      const std::vector<std::string> cfg_names = ReadFusionConfig(fusion_cfg, workspace.Model());
      listed = std::set<std::string>(cfg_names.begin(), cfg_names.end());
      if (listed.size() < names.size()) {
        LOG(INFO) << fusion_cfg << " lists " << listed.size() << " of the " << names.size()
                  << " views: only those are fused";
      }
    }
    Progress progress("template_fusion read", static_cast<int>(names.size()));
    std::vector<std::string> photometric_only;  // --input_type auto took their first estimate
    std::vector<std::string> without_map;  // listed, but no map to read
    for (size_t idx = 0; idx < names.size(); ++idx) {
      const std::string& name = names[idx];
      progress.Start(static_cast<int>(idx), name);
      if (listed.count(name) == 0) {
        progress.Stage("not in stereo/fusion.cfg, skipped");
        continue;
      }
      std::string type = options.input_type;
      if (type == "auto") {
        type = ExistsFile(workspace.DepthMapPath(name, "geometric")) ? "geometric" : "photometric";
        if (type == "photometric" && ExistsFile(workspace.DepthMapPath(name, type))) {
          photometric_only.push_back(name);
        }
      }
      const std::string depth_path = workspace.DepthMapPath(name, type);
      if (!ExistsFile(depth_path)) {
        progress.Stage("no " + type + " depth map, skipped");
        without_map.push_back(name);
        continue;
      }
      FusionView view;
      view.name = name;
      view.depth = ReadMat(depth_path);
      THROW_IF(view.depth.Channels() != 1, depth_path << ": a depth map needs 1 channel, not "
                                                      << view.depth.Channels());
      // COLMAP writes smaller depth maps with --PatchMatchStereo.max_image_size.
      const StereoCamera camera = workspace.ViewCamera(name).ScaledToMap(
          view.depth.Width(), view.depth.Height(), depth_path);
      view.K = camera.K;
      view.R = camera.R;
      view.t = camera.t;
      const std::string normal_path = workspace.NormalMapPath(name, type);
      if (ExistsFile(normal_path)) {
        view.normal = ReadMat(normal_path);
        THROW_IF(view.normal.Channels() != 3 || view.normal.Width() != view.depth.Width() ||
                     view.normal.Height() != view.depth.Height(),
                 normal_path << ": a normal map needs 3 channels and the size of its depth map "
                             << depth_path);
      } else {
        // colmap stereo_fusion needs normal maps; we can do without them.
        progress.Stage("no normal map " + normal_path + ": normals from the depth map");
        view.normal = NormalMapFromDepthMap(view.depth, view.K);
      }
      view.rgb = ResizeNearest(workspace.ReadViewRgb(name), view.depth.Width(),
                               view.depth.Height());
      view.CropToDepth();
      views.push_back(std::move(view));
      image_idx_of_view.push_back(static_cast<uint32_t>(workspace.ImageIdx(name)));
    }
    progress.Finish();
    // Mixed maps are worth a word: a view whose geometric pass did not run (or failed) brings
    // depths that no source view confirmed. All first estimates (a single-pass stereo) are not.
    if (!photometric_only.empty() && photometric_only.size() < views.size()) {
      LOG(WARNING) << photometric_only.size() << " of " << views.size()
                   << " views have no .geometric depth map: fused from their .photometric one "
                      "(the first estimate, unfiltered by the source views' agreement): "
                   << JoinStrings(photometric_only, ", ");
    }
    // A stereo run not finished yet (a job of an array still running) leaves views out: said
    // once, as colmap stereo_fusion says "Ignoring image" for each.
    if (!without_map.empty() && !views.empty()) {
      LOG(WARNING) << without_map.size() << " of the " << without_map.size() + views.size()
                   << " views to fuse have no depth map and are left out: "
                   << JoinFirstNames(without_map);
    }
    THROW_IF(views.empty(),
             workspace.StereoPath()
                 << ": no depth map (stereo/depth_maps/<image>.<type>.bin) to fuse"
                 << (listed.empty() ? " (stereo/fusion.cfg lists no view)" : "")
                 << "; compute them first (hairmvs orientation_stereo or patch_match_stereo, or "
                    "pipeline --stages orientation,stereo)");
  }

  const FusionOutput fusion = FuseViews(views, options, timings);

  TemplateFusionResult result;
  {
    ScopedStageTimer timer(timings, "write");
    std::vector<FusedPoint> points(fusion.fused.Size());
    for (size_t i = 0; i < points.size(); ++i) {
      points[i].xyz = fusion.fused.xyz[i];
      points[i].normal = fusion.fused.normal[i];
      for (int k = 0; k < 3; ++k) points[i].rgb[k] = fusion.fused.rgb[i][k];
      for (uint32_t v : fusion.fused.visible_views[i]) {
        points[i].visible_image_idxs.push_back(image_idx_of_view[v]);
      }
    }
    result.fused_path = JoinPaths(workspace_path, "fused.ply");
    WriteFusedPly(result.fused_path, points);
    result.mesh_path = JoinPaths(workspace_path, "meshed-hair.ply");
    WriteMeshPly(result.mesh_path, ToTriangleMesh(fusion.final_mesh));
    if (options.write_intermediate) {
      FusionMesh coarse = fusion.coarse, refined = fusion.refined;
      coarse.ComputeVertexNormals();
      refined.ComputeVertexNormals();
      WriteMeshPly(JoinPaths(workspace_path, "meshed-coarse-template.ply"), ToTriangleMesh(coarse));
      WriteMeshPly(JoinPaths(workspace_path, "meshed-refined-template.ply"),
                   ToTriangleMesh(refined));
    }
  }

  result.num_views = static_cast<int>(views.size());
  result.num_input_points = fusion.num_input_points;
  result.num_fused_points = static_cast<int>(fusion.fused.Size());
  result.num_poisson_points = fusion.num_poisson_points;
  result.coarse_num_vertices = static_cast<int>(fusion.coarse.vertices.size());
  result.coarse_num_faces = static_cast<int>(fusion.coarse.faces.size());
  result.final_num_vertices = static_cast<int>(fusion.final_mesh.vertices.size());
  result.final_num_faces = static_cast<int>(fusion.final_mesh.faces.size());
  fusion.final_mesh.FaceComponents(&result.num_components);
  result.euler_characteristic = fusion.final_mesh.EulerCharacteristic();
  result.octree_cell_m = fusion.cell_m;
  result.median_detail_offset_m = fusion.detail.median_abs_offset_m;
  result.seconds = total_timer.ElapsedSeconds();
  result.peak_memory_mib = PeakResidentMemoryMiB();
  return result;
}

}  // namespace hairmvs
