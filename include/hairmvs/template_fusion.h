#pragma once
// Merging the depth maps of a workspace into one hair surface (method.md section 3, the
// paper's Section 4): points from all depth maps -> coarse template (Poisson, octree depth 6)
// -> refined template (embedded-deformation-graph non-rigid registration towards every depth
// map, Li et al. 2009) -> detail (offsets along the vertex normals from the depth maps).
//
// Outputs in the workspace root, each written atomically:
//   fused.ply + fused.ply.vis   the points, exactly as COLMAP's stereo_fusion writes them
//   meshed-hair.ply             the final mesh (binary, vertex normals and colours)
//   meshed-coarse-template.ply, meshed-refined-template.ply   with write_intermediate

#include <string>

#include "src/core/timer.h"

namespace hairmvs {

struct TemplateFusionOptions {
  // Depth maps to read: "geometric" or "photometric" (stereo/depth_maps/<name>.<type>.bin);
  // "auto" takes geometric where it exists, else photometric.
  std::string input_type = "auto";
  // Every point_stride_px-th pixel in each direction of each depth map becomes a point:
  // neighbouring pixels see the same strands, and 2 keeps a quarter of ~100k hair pixels.
  int point_stride_px = 2;
  // fused.ply: points merged on a voxel grid whose cell is this many times the median pixel
  // footprint (depth / focal length), so the density does not depend on the scene's scale.
  double fused_voxel_size_px = 2.0;
  // A point is seen by a view when it projects inside that view's depth map and its depth
  // there agrees within this fraction of the depth (1% = 6 mm at 0.6 m: hair is a volume).
  double visibility_depth_tolerance = 0.01;
  // Points seen by fewer views (its own included) are dropped: outliers of one map alone.
  int min_num_visible_views = 2;

  // Coarse template: Poisson surface reconstruction at this octree depth (paper: 6, 64^3).
  int poisson_depth = 6;
  // Poisson's bounding-box scale (Kazhdan's --scale): room around the points.
  double poisson_scale = 1.1;
  // Points handed to Poisson: merged on a voxel grid of this fraction of an octree cell;
  // Poisson at depth 6 needs far fewer points than the depth maps have.
  double poisson_sample_cells = 0.25;
  // Trim low-density parts: faces farther than this many octree cells from every input
  // sample are where Poisson closed the surface without data (neck, crown seen by no view).
  double trim_distance_cells = 1.0;
  // ... but never closer than this many sample spacings (the voxel the samples were merged
  // on), for depth maps coarser than the octree.
  double trim_min_sample_spacings = 1.5;
  // Connected components with fewer faces than this fraction of the largest are dropped.
  double min_component_fraction = 0.05;
  // Before refinement the template is subdivided (Loop: smooth, it draws a coarse template a
  // little inside a convex surface, which the refinement's fit takes back) until its mean edge
  // is at most this many median pixel footprints, so the detail step has vertices to carry
  // detail.
  double target_edge_length_px = 3.0;
  // ... but the subdivided template keeps at most this many vertices.
  int max_mesh_vertices = 400000;

  // Refined template: embedded deformation graph (Li, Adams, Guibas, Pauly 2009).
  // Graph nodes are sampled on the template this many octree cells apart.
  double node_spacing_cells = 2.5;
  // Each vertex is deformed by this many nearest nodes (Sumner et al. 2007 use 4).
  int num_node_neighbors = 4;
  // Rounds of registration; each resets the rest state to the current surface (paper: 10).
  int num_rounds = 10;
  // Weights of the first round; rigidity and smoothness are multiplied by
  // regularization_decay after every round (Li et al.: relax the stiffness progressively).
  double fit_weight = 1.0;
  double rigidity_weight = 10.0;
  double smoothness_weight = 10.0;
  double regularization_decay = 0.6;
  // A depth map pulls a vertex only where its surface is within this many octree cells along
  // the line of sight: farther is another layer or an occluder.
  double max_fit_distance_cells = 2.0;
  // At most this many vertices carry fit terms per round (a uniform subsample): the graph
  // has far fewer degrees of freedom.
  int max_fit_vertices = 20000;
  int max_solver_iterations = 10;

  // Detail: offsets along the vertex normals, median over the views that see the vertex,
  // at most this many octree cells.
  double max_detail_offset_cells = 1.0;
  // Views whose line of sight makes a larger angle with the vertex normal are not used for
  // the detail (grazing views measure the offset poorly).
  double max_detail_view_angle_deg = 70.0;
  // The offsets as one linear least-squares problem (Li et al. 2009's linear deformation):
  // each vertex's median offset as its target, plus this weight times the squared difference
  // of the offsets across each mesh edge, so that vertices without a target take their
  // neighbours' offsets rather than 0. 0: each vertex its own median (no solve). Off by
  // default: it trades the visible hair's coverage for accuracy, the hair's strands being a
  // rough volume that the per-vertex offsets reach into (measured on the true depths with 1 mm
  // of noise, `import_ground_truth --noise_m 0.001` then `template_fusion` and `evaluate_mesh`;
  // surface accuracy median / within 2 mm: synth_handheld 0.478 mm / 67.5% at 0, 0.474 / 66.4%
  // at 0.01, 0.461 / 60.4% at 0.1, 0.438 / 50.1% at 2; synth_straight_gantry 0.459 / 67.6%,
  // 0.454 / 66.4%, 0.437 / 61.5%, 0.413 / 52.5%).
  double detail_smoothness_weight = 0.0;

  int num_threads = 2;
  // Also write the coarse and refined templates.
  bool write_intermediate = false;

  template <typename Visitor>
  void ForEachField(Visitor&& v) {
    v("input_type", &input_type, "depth maps to read: geometric, photometric or auto");
    v("point_stride_px", &point_stride_px, "take every n-th pixel of each depth map");
    v("fused_voxel_size_px", &fused_voxel_size_px,
      "fused.ply voxel size in median pixel footprints");
    v("visibility_depth_tolerance", &visibility_depth_tolerance,
      "relative depth agreement for a view to see a point");
    v("min_num_visible_views", &min_num_visible_views, "drop points seen by fewer views");
    v("poisson_depth", &poisson_depth, "octree depth of the coarse Poisson template (paper: 6)");
    v("poisson_scale", &poisson_scale, "Poisson bounding-box scale");
    v("poisson_sample_cells", &poisson_sample_cells,
      "voxel size of the points given to Poisson, in octree cells");
    v("trim_distance_cells", &trim_distance_cells,
      "trim faces farther than this from every sample, in octree cells");
    v("trim_min_sample_spacings", &trim_min_sample_spacings,
      "minimum trim distance, in sample spacings");
    v("min_component_fraction", &min_component_fraction,
      "drop components smaller than this fraction of the largest");
    v("target_edge_length_px", &target_edge_length_px,
      "subdivide the template to this edge length, in pixel footprints");
    v("max_mesh_vertices", &max_mesh_vertices, "max vertices of the subdivided template");
    v("node_spacing_cells", &node_spacing_cells, "deformation graph node spacing, octree cells");
    v("num_node_neighbors", &num_node_neighbors, "nodes deforming each vertex");
    v("num_rounds", &num_rounds, "non-rigid registration rounds (paper: 10)");
    v("fit_weight", &fit_weight, "weight of the depth-map fit term");
    v("rigidity_weight", &rigidity_weight, "initial weight of the rigidity term");
    v("smoothness_weight", &smoothness_weight, "initial weight of the smoothness term");
    v("regularization_decay", &regularization_decay,
      "factor applied to rigidity and smoothness after each round");
    v("max_fit_distance_cells", &max_fit_distance_cells,
      "max distance along the line of sight for a fit term, octree cells");
    v("max_fit_vertices", &max_fit_vertices, "max vertices with fit terms per round");
    v("max_solver_iterations", &max_solver_iterations, "Ceres iterations per round");
    v("max_detail_offset_cells", &max_detail_offset_cells, "max detail offset, octree cells");
    v("max_detail_view_angle_deg", &max_detail_view_angle_deg,
      "max angle between line of sight and vertex normal for detail");
    v("detail_smoothness_weight", &detail_smoothness_weight,
      "weight of the detail offsets' differences across mesh edges (0: per-vertex medians)");
    v("num_threads", &num_threads,
      "threads for the fused points, fit targets, Ceres and detail (Poisson runs on one)");
    v("write_intermediate", &write_intermediate, "also write the coarse and refined templates");
  }
  bool Check(std::string* error) const;
};

struct TemplateFusionResult {
  int num_views = 0;
  int num_input_points = 0;  // pixels taken from the depth maps
  int num_fused_points = 0;  // in fused.ply
  int num_poisson_points = 0;
  int coarse_num_vertices = 0;
  int coarse_num_faces = 0;
  int final_num_vertices = 0;
  int final_num_faces = 0;
  int num_components = 0;
  int euler_characteristic = 0;
  double octree_cell_m = 0;
  double median_detail_offset_m = 0;  // median |offset| of the detail step
  double seconds = 0;
  double peak_memory_mib = 0;
  std::string fused_path;
  std::string mesh_path;

  std::string BriefReport() const;
};

// Reads every depth map of the workspace (with its normal map, or normals computed from the
// depth), fuses and meshes them, and writes the outputs listed above. Throws hairmvs::Error
// naming the file for a missing or malformed input and when no depth map exists.
TemplateFusionResult RunTemplateFusion(const std::string& workspace_path,
                                       const TemplateFusionOptions& options,
                                       StageTimings* timings);

}  // namespace hairmvs
