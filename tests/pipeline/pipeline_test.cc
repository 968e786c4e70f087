// End to end on a tiny synthesised set (one gantry T group, 480 x 320): synthesize,
// orientation fields, orientation stereo and template fusion, then the evaluations against the
// set's own ground truth. The bounds are the bars that this size meets (completeness,
// 3D accuracy of the depth maps, mesh accuracy); the per-pixel depth error is printed, not
// bounded (hair is a volume: see the README of the shared data sets).

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/ply.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/evaluation.h"
#include "hairmvs/orientation_fields.h"
#include "hairmvs/orientation_stereo.h"
#include "hairmvs/synthesize.h"
#include "hairmvs/template_fusion.h"
#include "src/core/file_util.h"
#include "src/evaluation/depth_evaluation.h"
#include "src/evaluation/ground_truth.h"
#include "src/core/test_util.h"

namespace hairmvs {
namespace {

TEST(Pipeline, SynthesizedSetEndToEnd) {
  const std::string root = testing_util::MakeTestDir("pipeline_test");

  SynthesizeOptions synth;
  synth.output_path = root;
  synth.width = 480;
  synth.num_strands = 20000;
  synth.seed = 3;
  RunSynthesize(synth);
  const std::string workspace_path = JoinPaths(root, "dense");
  const std::string gt_path = JoinPaths(root, "gt");

  StageTimings timings;
  OrientationFieldsRunOptions field_run;
  RunOrientationFields(workspace_path, OrientationFieldOptions(), field_run, &timings);
  const OrientationStereoResult stereo =
      RunOrientationStereo(workspace_path, {}, OrientationStereoOptions(), &timings);
  const TemplateFusionResult fusion =
      RunTemplateFusion(workspace_path, TemplateFusionOptions(), &timings);

  // Every view has its COLMAP-layout maps, of the image's size.
  const Workspace workspace = Workspace::Read(workspace_path);
  EXPECT_EQ(stereo.num_views, static_cast<int>(workspace.ImageNames().size()));
  for (const std::string& name : workspace.ImageNames()) {
    const FloatMap depth = ReadMat(workspace.DepthMapPath(name));
    const FloatMap normals = ReadMat(workspace.NormalMapPath(name));
    EXPECT_EQ(depth.Width(), static_cast<int>(workspace.CameraOf(name).width));
    EXPECT_EQ(depth.Channels(), 1);
    EXPECT_EQ(normals.Channels(), 3);
    EXPECT_EQ(normals.Width(), depth.Width());
  }
  const std::vector<FusedPoint> fused = ReadFusedPly(JoinPaths(workspace_path, "fused.ply"));
  EXPECT_EQ(static_cast<int>(fused.size()), fusion.num_fused_points);
  EXPECT_GT(fused.size(), 1000u);
  const TriangleMesh mesh = ReadMeshPly(JoinPaths(workspace_path, "meshed-hair.ply"));
  EXPECT_GT(mesh.faces.size(), 1000u);
  EXPECT_EQ(mesh.normals.size(), mesh.vertices.size());

  const StrandDistance strands(ReadGroundTruthStrands(gt_path), 5e-4);
  // The depth maps as estimated (.photometric) cover the hair; the consistency-filtered ones
  // (.geometric) keep most of it and drop more bad pixels than good ones.
  DepthEvaluationOptions photometric_options;
  photometric_options.depth_type = "photometric";
  const DepthEvaluationResult estimated =
      EvaluateDepthMaps(workspace_path, gt_path, photometric_options, strands);
  std::printf("%s", estimated.Table().c_str());
  EXPECT_GE(estimated.overall.completeness, 0.90);
  EXPECT_LE(estimated.overall.accuracy_3d_median_mm, 1.5);
  const DepthEvaluationResult depth =
      EvaluateDepthMaps(workspace_path, gt_path, DepthEvaluationOptions(), strands);
  std::printf("%s", depth.Table().c_str());
  EXPECT_GE(depth.overall.completeness, 0.75);
  EXPECT_LT(depth.overall.median_abs_error_mm, estimated.overall.median_abs_error_mm);
  EXPECT_LT(depth.overall.mean_abs_error_mm, estimated.overall.mean_abs_error_mm);
  EXPECT_LE(depth.overall.accuracy_3d_median_mm, 1.5);

  const MeshEvaluationResult mesh_eval =
      EvaluateMesh(JoinPaths(workspace_path, "meshed-hair.ply"), gt_path, workspace_path,
                   MeshEvaluationOptions(), strands);
  std::printf("%s", mesh_eval.Report().c_str());
  EXPECT_LE(mesh_eval.accuracy_vertices.median_mm, 2.0);
  std::printf("%s", timings.Table().c_str());
  std::filesystem::remove_all(root);
}

}  // namespace
}  // namespace hairmvs
