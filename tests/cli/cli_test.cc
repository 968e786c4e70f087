// The hairmvs executable, run as a user runs it: what only the binary shows (the command table,
// each command's option parser, the pipeline's wiring of one stage's options into the next).

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/ply.h"
#include "colmap_ext/test_util.h"
#include "colmap_ext/workspace.h"
#include "src/core/file_util.h"

namespace hairmvs {
namespace {

struct CommandOutput {
  int exit_code = -1;
  std::string text;  // stdout and stderr
};

// Runs the shell command `command_line`, its stderr with its stdout.
CommandOutput RunCommand(const std::string& command_line) {
  const std::string command = command_line + " 2>&1";
  CommandOutput output;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return output;
  char buffer[4096];
  size_t n;
  while ((n = fread(buffer, 1, sizeof(buffer), pipe)) > 0) output.text.append(buffer, n);
  const int status = pclose(pipe);
  output.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return output;
}

// Runs `hairmvs <args>`.
CommandOutput RunHairmvs(const std::string& args) {
  return RunCommand(std::string("'") + HAIRMVS_EXECUTABLE + "' " + args);
}

// A long command ends with its stage table, naming `stages`, and its peak memory.
void ExpectRunSummary(const std::string& text, const std::vector<std::string>& stages) {
  for (const std::string& stage : stages) {
    EXPECT_NE(text.find("\n  " + stage + " "), std::string::npos) << stage << " in:\n" << text;
  }
  EXPECT_NE(text.find("\nPeak resident memory: "), std::string::npos) << text;
}

// A T group of views 160 px wide of sparse hair, with its truth, in `dir` (a few seconds);
// returns its dense workspace.
std::string SynthesizeSmallSet(const std::string& dir) {
  const CommandOutput output =
      RunHairmvs("synthesize --output_path " + dir + " --width 160 --num_strands 20000");
  EXPECT_EQ(output.exit_code, 0) << output.text;
  ExpectRunSummary(output.text, {"hair", "render", "write"});
  return JoinPaths(dir, "dense");
}

// The command names that `hairmvs help` lists.
std::vector<std::string> CommandNames() {
  std::istringstream lines(RunHairmvs("help").text);
  std::vector<std::string> names;
  bool in_table = false;
  for (std::string line; std::getline(lines, line);) {
    if (line == "Commands:") {
      in_table = true;
    } else if (in_table && line.size() > 2 && line[0] == ' ') {
      names.push_back(line.substr(2, line.find(' ', 2) - 2));
    }
  }
  return names;
}

// Every command builds its parser (one that binds a variable to two options throws there)
// and prints its help.
TEST(Cli, EveryCommandPrintsItsHelp) {
  const std::vector<std::string> names = CommandNames();
  EXPECT_GE(names.size(), 13u);
  for (const std::string& name : names) {
    const CommandOutput output = RunHairmvs(name + " -h");
    EXPECT_EQ(output.exit_code, 0) << name << ":\n" << output.text;
    EXPECT_NE(output.text.find("Options:"), std::string::npos) << name << ":\n" << output.text;
  }
}

// A value given on the command line is the one the command checks, and the check names the
// option as the command spells it.
TEST(Cli, OptionsReachTheirCommandAndErrorsNameThem) {
  const std::string dir = testing_util::MakeTestDir("cli_options");
  CommandOutput output =
      RunHairmvs("template_fusion --workspace_path " + dir + " --TemplateFusion.num_threads 0");
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find("TemplateFusion.num_threads must be in [1, 256]"), std::string::npos)
      << output.text;
  output = RunHairmvs("evaluate_depth --workspace_path " + dir + " --ground_truth_path " + dir +
                      " --depth_type colour");
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find("invalid option: --depth_type must be geometric or photometric"),
            std::string::npos)
      << output.text;
  output = RunHairmvs("evaluate_mesh --mesh m.ply --ground_truth_path " + dir +
                      " --surface_sample_spacing_m 0");
  EXPECT_NE(output.text.find("--surface_sample_spacing_m must be > 0"), std::string::npos)
      << output.text;
  // Every section of the pipeline is checked before its first stage runs.
  output = RunHairmvs("pipeline --workspace_path " + dir + " --SourceViews.max_num_source_views 0");
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find("--SourceViews: max_num_source_views must be >= 1"),
            std::string::npos)
      << output.text;
  output = RunHairmvs("pipeline --workspace_path " + dir + " --stages ''");
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find("--stages: no stage given"), std::string::npos) << output.text;
  const std::string file = JoinPaths(dir, "a_file");
  WriteFileAtomically(file, [](std::ostream& out) { out << "not a workspace"; });
  output = RunHairmvs("pipeline --workspace_path " + file + " --image_path " + dir +
                      " --input_path " + dir);
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find("--workspace_path " + file + " is a file, not a folder"),
            std::string::npos)
      << output.text;
  // A missing ground truth folder is named before colmap image_undistorter runs, not after the
  // stereo and the fusion.
  const std::string no_gt = JoinPaths(dir, "no_gt");
  output = RunHairmvs("pipeline --workspace_path " + JoinPaths(dir, "ws") + " --image_path " +
                      dir + " --input_path " + dir + " --ground_truth_path " + no_gt);
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find("Missing ground truth folder (--ground_truth_path): " + no_gt),
            std::string::npos)
      << output.text;
  EXPECT_FALSE(ExistsDir(JoinPaths(dir, "ws")));
  output = RunHairmvs("import_ground_truth --ground_truth_path " + dir + " --workspace_path " +
                      dir + " --output_path " + JoinPaths(dir, "out") + " --median_filter_px 101");
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find("--median_filter_px must be 0 or odd, at most 99"), std::string::npos)
      << output.text;
  EXPECT_FALSE(ExistsDir(JoinPaths(dir, "out")));
  // Control bytes quoted in an error (here a path; a config file's line alike) are escaped.
  output = RunHairmvs("workspace_info --workspace_path '" + JoinPaths(dir, "x\x1b]0;t\x07") + "'");
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find(JoinPaths(dir, "x\\x1b]0;t\\x07")), std::string::npos) << output.text;
  EXPECT_EQ(output.text.find('\x1b'), std::string::npos) << output.text;
  std::filesystem::remove_all(dir);
}

// The pipeline evaluates the maps its stereo stage wrote: single-pass .photometric maps too.
TEST(Cli, PipelineEvaluatesTheMapsItsStereoWrote) {
  const std::string dir = testing_util::MakeTestDir("cli_pipeline");
  const std::string workspace = SynthesizeSmallSet(dir);
  CommandOutput output = RunHairmvs(
      "pipeline --workspace_path " + workspace + " --ground_truth_path " + JoinPaths(dir, "gt") +
      " --stages orientation,stereo --OrientationStereo.geom_consistency 0" +
      " --OrientationStereo.single_pass_type photometric");
  ASSERT_EQ(output.exit_code, 0) << output.text;
  EXPECT_TRUE(ExistsFile(JoinPaths(workspace, "stereo", "depth_maps", "g0_c.png.photometric.bin")));
  EXPECT_FALSE(ExistsFile(JoinPaths(workspace, "stereo", "depth_maps", "g0_c.png.geometric.bin")));
  const std::string summary = JoinPaths(workspace, "stereo", "evaluation", "depth_evaluation.json");
  ASSERT_TRUE(ExistsFile(summary)) << output.text;
  EXPECT_NE(ReadTextFile(summary).find("\"depth_type\": \"photometric\""), std::string::npos);
  EXPECT_NE(output.text.find("overall"), std::string::npos) << output.text;
  ExpectRunSummary(output.text, {"filter kernel", "cost volume", "evaluate_depth"});
  // The evaluators on their own end the same way.
  output = RunHairmvs("evaluate_depth --workspace_path " + workspace + " --ground_truth_path " +
                      JoinPaths(dir, "gt") + " --depth_type photometric");
  ASSERT_EQ(output.exit_code, 0) << output.text;
  ExpectRunSummary(output.text, {"true strands", "read maps and truth", "per-pixel errors",
                                 "3D distances", "error pictures", "summary"});
  std::filesystem::remove_all(dir);
}

// The pipeline from photos with masks drawn on them, run again as the README says to finish a
// stopped run: the workspace it made holds a mask for every image, so the second run goes on
// with those rather than refusing --photo_mask_path.
TEST(Cli, PipelineFromPhotosWithMasksRunsAgain) {
  const std::string dir = testing_util::MakeTestDir("cli_pipeline_photo_masks");
  const std::string set = SynthesizeSmallSet(dir);
  // The set's undistorted images and model stand for the photos (PINHOLE: undistorting keeps
  // them), its masks for the masks drawn on them (<photo name>.png).
  const std::string photo_masks = JoinPaths(dir, "photo_masks");
  CreateDirs(photo_masks);
  for (const auto& entry : std::filesystem::directory_iterator(JoinPaths(set, "masks"))) {
    const std::string name = entry.path().filename().string();  // <image>.png.png
    std::filesystem::copy_file(entry.path(),
                               JoinPaths(photo_masks, name.substr(0, name.size() - 4)));
  }
  const std::string dense = JoinPaths(dir, "from_photos");
  const std::string run = "pipeline --workspace_path " + dense + " --image_path " +
                          JoinPaths(set, "images") + " --input_path " + JoinPaths(set, "sparse") +
                          " --photo_mask_path " + photo_masks + " --stages orientation";
  CommandOutput output = RunHairmvs(run);
  ASSERT_EQ(output.exit_code, 0) << output.text;
  EXPECT_TRUE(Workspace::Read(dense).ImagesWithoutMask().empty());
  output = RunHairmvs(run);
  ASSERT_EQ(output.exit_code, 0) << output.text;
  EXPECT_NE(output.text.find("exists with a mask for every image"), std::string::npos)
      << output.text;
  EXPECT_NE(output.text.find("The workspace " + dense + " exists and is used as it is"),
            std::string::npos)
      << output.text;
  // Without a mask for some image it is refused, naming undistort_masks.
  std::filesystem::remove(JoinPaths(dense, "masks", "g0_c.png.png"));
  output = RunHairmvs(run);
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find("undistort_masks"), std::string::npos) << output.text;
  // The set's truth as a workspace: its stage table too.
  output = RunHairmvs("import_ground_truth --ground_truth_path " + JoinPaths(dir, "gt") +
                      " --workspace_path " + set + " --output_path " + JoinPaths(dir, "truth"));
  ASSERT_EQ(output.exit_code, 0) << output.text;
  ExpectRunSummary(output.text,
                   {"workspace frame", "read truth", "labels, filter, noise", "normals, write"});
  std::filesystem::remove_all(dir);
}

// What the drop-in writes, colmap stereo_fusion fuses with its defaults: also in a workspace
// without stereo/*.cfg (not made by colmap image_undistorter), whose fusion.cfg the stereo
// writes (colmap aborted without it).
TEST(Cli, ColmapFusesTheDropInsMapsWithItsDefaults) {
  if (!ExistsFile(HAIRMVS_COLMAP_EXECUTABLE)) {
    GTEST_SKIP() << "colmap executable not found: " << HAIRMVS_COLMAP_EXECUTABLE;
  }
  const std::string dir = testing_util::MakeTestDir("cli_colmap_fusion");
  const std::string workspace = SynthesizeSmallSet(dir);
  for (const char* cfg : {"patch-match.cfg", "fusion.cfg"}) {
    std::filesystem::remove(JoinPaths(workspace, "stereo", cfg));
  }
  CommandOutput output = RunHairmvs("patch_match_stereo --workspace_path " + workspace);
  ASSERT_EQ(output.exit_code, 0) << output.text;
  const std::string fused = JoinPaths(dir, "fused.ply");
  output = RunCommand(std::string("'") + HAIRMVS_COLMAP_EXECUTABLE +
                      "' stereo_fusion --workspace_path " + workspace +
                      " --input_type geometric --output_path " + fused);
  ASSERT_EQ(output.exit_code, 0) << output.text;
  const std::vector<FusedPoint> points = ReadFusedPly(fused);
  std::printf("colmap stereo_fusion, defaults: %zu points\n", points.size());
  // About 75 on this 160 px T group (colmap's threads vary it): its strands are a twentieth of
  // a pixel wide, so that few depths of its rough maps meet colmap's default consistency.
  EXPECT_GT(points.size(), 30u);
  for (const FusedPoint& p : points) {
    ASSERT_FALSE(p.visible_image_idxs.empty());
    for (uint32_t idx : p.visible_image_idxs) ASSERT_LT(idx, 4u);
  }
  std::filesystem::remove_all(dir);
}

// The drop-in for colmap patch_match_stereo: its filter 0 keeps every estimate (the geometric
// pass still runs, as colmap's), a value it maps that the stereo refuses is named as the user
// typed it, and the options colmap gives every command are accepted with a warning.
TEST(Cli, PatchMatchStereoTakesColmapsOptions) {
  const std::string dir = testing_util::MakeTestDir("cli_patch_match");
  const std::string workspace = SynthesizeSmallSet(dir);
  CommandOutput output;
  const std::string run = "patch_match_stereo --workspace_path " + workspace +
                          " --workspace_format COLMAP --OrientationStereo.skip_existing 0";
  auto num_depths = [&](const std::string& type) {
    const FloatMap map =
        ReadMat(JoinPaths(workspace, "stereo", "depth_maps", "g0_c.png." + type + ".bin"));
    return std::count_if(map.Data().begin(), map.Data().end(), [](float d) { return d > 0; });
  };
  // The stereo sets the fields' levels itself: the field option that would do it warns.
  output = RunHairmvs(run + " --log_to_stderr 1 --random_seed 3 --OrientationField.num_levels 2");
  ASSERT_EQ(output.exit_code, 0) << output.text;
  EXPECT_NE(output.text.find("log_to_stderr"), std::string::npos) << output.text;
  EXPECT_NE(output.text.find("--OrientationField.num_levels is ignored by hairmvs: the stereo "
                             "computes the fields' levels from --OrientationStereo.num_levels"),
            std::string::npos)
      << output.text;
  const long filtered = num_depths("geometric");
  output = RunHairmvs(run + " --PatchMatchStereo.filter 0");
  ASSERT_EQ(output.exit_code, 0) << output.text;
  EXPECT_NE(output.text.find("geometric consistency"), std::string::npos) << output.text;
  const long unfiltered = num_depths("geometric");
  EXPECT_GT(unfiltered, filtered);
  // A filter given beside filter 0, which would override it, is refused before any work.
  output = RunHairmvs(run + " --PatchMatchStereo.filter 0 --OrientationStereo.min_confidence 0.1");
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find("--OrientationStereo.min_confidence filters them"), std::string::npos)
      << output.text;
  // A colmap option and the hairmvs option it sets, both on the command line: refused before
  // any work, rather than one silently winning.
  output = RunHairmvs(run + " --PatchMatchStereo.max_image_size 100 "
                            "--OrientationStereo.max_image_size 50");
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find("--PatchMatchStereo.max_image_size and "
                             "--OrientationStereo.max_image_size set the same option: give one "
                             "or the other"),
            std::string::npos)
      << output.text;
  output = RunHairmvs(run + " --config_path a.cfg --SourceViews.config_path b.cfg");
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find("--config_path and --SourceViews.config_path set the same file"),
            std::string::npos)
      << output.text;
  output = RunHairmvs(run + " --PatchMatchStereo.max_image_size 0");
  EXPECT_NE(output.exit_code, 0);
  EXPECT_NE(output.text.find("(max_image_size is set by --PatchMatchStereo.max_image_size)"),
            std::string::npos)
      << output.text;
  // A project file as colmap writes it: its options apply, but colmap's defaults where
  // hairmvs's differ on purpose leave hairmvs's, so the maps are the defaults' ones.
  const std::string ini = JoinPaths(dir, "project.ini");
  WriteFileAtomically(ini, [](std::ostream& out) {
    out << "log_level=2\n[PatchMatchStereo]\ngeom_consistency=true\nfilter=true\n"
           "max_image_size=-1\nwindow_radius=5\nfilter_min_num_consistent=2\n"
           "geom_consistency_max_cost=3\nfilter_geom_consistency_max_cost=1\n[StereoFusion]\n"
           "min_num_pixels=5\n";
  });
  output = RunHairmvs(run + " --project_path " + ini);
  ASSERT_EQ(output.exit_code, 0) << output.text;
  EXPECT_NE(output.text.find("are colmap's defaults: not applied"), std::string::npos)
      << output.text;
  EXPECT_EQ(num_depths("geometric"), filtered);
  // The command line's hairmvs option wins over the file's colmap one that sets it.
  output = RunHairmvs(run + " --project_path " + ini + " --OrientationStereo.max_image_size 80");
  ASSERT_EQ(output.exit_code, 0) << output.text;
  EXPECT_EQ(
      ReadMat(JoinPaths(workspace, "stereo", "depth_maps", "g0_c.png.geometric.bin")).Width(),
      80);
  EXPECT_NE(output.text.find("PatchMatchStereo.max_image_size (--OrientationStereo.max_image_size "
                             "given): not applied"),
            std::string::npos)
      << output.text;
  output = RunHairmvs(run);  // the maps of the defaults again
  ASSERT_EQ(output.exit_code, 0) << output.text;
  // The geometric pass alone runs without the resume colmap's drop-in turns on by default.
  output = RunHairmvs("patch_match_stereo --workspace_path " + workspace +
                      " --OrientationStereo.geom_consistency_only 1");
  ASSERT_EQ(output.exit_code, 0) << output.text;
  EXPECT_EQ(num_depths("geometric"), filtered);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hairmvs
