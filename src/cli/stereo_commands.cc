// hairmvs orientation_stereo: orientation-field depth maps of a COLMAP dense workspace.
// hairmvs patch_match_stereo: the same, behind colmap patch_match_stereo's command line.

#include <algorithm>
#include <cstdio>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "colmap_ext/source_views.h"
#include "hairmvs/orientation_fields.h"
#include "hairmvs/orientation_stereo.h"
#include "src/cli/command_registry.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/option_parser.h"
#include "src/core/timer.h"
#include "src/opencl/opencl_options.h"

namespace hairmvs {
namespace {

void PrintSummary(const OrientationStereoResult& result, const StageTimings& timings) {
  std::printf("%s\n%s", result.BriefReport().c_str(), RunSummary(timings).c_str());
}

int RunOrientationStereoCommand(int argc, char** argv) {
  std::string workspace_path;
  std::vector<std::string> image_names;
  OrientationStereoOptions options;
  SourceViewOptions source_options;
  OrientationFieldOptions field_options;
  OpenCLOptions opencl_options;
  OptionParser parser("orientation_stereo",
                      "Depth maps of a COLMAP dense workspace from orientation fields (Luo et al. "
                      "2012, Section 3): writes stereo/depth_maps/<name>.photometric.bin (as "
                      "estimated) and <name>.geometric.bin (consistent with the source views), "
                      "normal maps likewise, and stereo/confidence_maps/.");
  parser.Add("workspace_path", &workspace_path, "COLMAP dense workspace", /*required=*/true);
  parser.Add("image_names", &image_names,
             "comma-separated reference images (default: all), e.g. to share a workspace "
             "between processes");
  parser.Add("write_png", &options.write_png, "also write coloured depth and normal pictures");
  parser.AddSection("OrientationStereo", &options);
  parser.AddSection("SourceViews", &source_options);
  parser.AddSection("OrientationField", &field_options,
                    OrientationStereoOptions::FieldOptionsSetHere());
  parser.AddSection("OpenCL", &opencl_options);
  if (!parser.Parse(argc, argv)) return 0;
  std::string error;
  THROW_IF(!opencl_options.Check(&error), "invalid --OpenCL options: " << error);
  std::printf("%s", parser.Values().c_str());
  StageTimings timings;
  const OrientationStereoResult result =
      RunOrientationStereo(workspace_path, image_names, options, &timings, opencl_options.device,
                           &source_options, &field_options);
  PrintSummary(result, timings);
  return 0;
}

// colmap patch_match_stereo's options that mean something here, mapped onto
// OrientationStereoOptions; the others are accepted with a warning.
int RunPatchMatchStereoCommand(int argc, char** argv) {
  std::string workspace_path;
  std::string workspace_format = "COLMAP";
  std::string config_path;
  int max_image_size = -1;
  double depth_min = -1, depth_max = -1, min_triangulation_angle = 1.0;
  bool geom_consistency = true, filter = true;
  OrientationStereoOptions options;
  // hairmvs's defaults, not COLMAP's (2, 1 px, 3 px): see OrientationStereoOptions.
  int filter_min_num_consistent = options.geom_consistency_min_views;
  double filter_geom_consistency_max_cost = options.geom_consistency_max_error_px;
  double filter_min_triangulation_angle = options.geom_consistency_min_triangulation_angle_deg;
  double geom_consistency_max_cost = options.geom_prior_max_error_px;
  // As colmap patch_match_stereo: views whose maps exist are skipped (a run resumes).
  options.skip_existing = true;
  SourceViewOptions source_options;
  OrientationFieldOptions field_options;
  OpenCLOptions opencl_options;
  OptionParser parser("patch_match_stereo",
                      "Drop-in for `colmap patch_match_stereo`: orientation-field depth maps in "
                      "COLMAP's layout (stereo/depth_maps/<name>.geometric.bin), ready for "
                      "`colmap stereo_fusion --input_type geometric`. As colmap's, it skips views "
                      "whose maps exist, so that an interrupted run resumes "
                      "(--OrientationStereo.skip_existing 0 computes them all again).");
  parser.Add("workspace_path", &workspace_path, "COLMAP dense workspace", /*required=*/true);
  parser.Add("workspace_format", &workspace_format, "COLMAP (PMVS is not supported)");
  parser.Add("write_png", &options.write_png, "also write coloured depth and normal pictures");
  parser.Add("PatchMatchStereo.max_image_size", &max_image_size,
             "longer side of the processing resolution (-1: full)");
  parser.Add("PatchMatchStereo.depth_min", &depth_min, "depth range start (-1: sparse points)");
  parser.Add("PatchMatchStereo.depth_max", &depth_max, "depth range end (-1: sparse points)");
  parser.Add("PatchMatchStereo.min_triangulation_angle", &min_triangulation_angle,
             "source views: minimum triangulation angle in degrees");
  parser.Add("PatchMatchStereo.geom_consistency", &geom_consistency,
             "write .photometric maps, then .geometric maps estimated again with the source "
             "views' maps as a prior and filtered by consistency with them (0: the "
             ".photometric maps alone)");
  parser.Add("PatchMatchStereo.geom_consistency_max_cost", &geom_consistency_max_cost,
             "geometric pass: reprojection error in px at which the sources' depth maps, as a "
             "prior, cost the most");
  parser.Add("PatchMatchStereo.filter_min_num_consistent", &filter_min_num_consistent,
             "views that must agree for a pixel to keep its depth (its sources and the views "
             "looking the same way: see --OrientationStereo.geom_consistency_max_view_angle_deg)");
  parser.Add("PatchMatchStereo.filter_min_triangulation_angle", &filter_min_triangulation_angle,
             "a view meeting the pixel's ray at a smaller angle (degrees) does not agree");
  parser.Add("PatchMatchStereo.filter_geom_consistency_max_cost",
             &filter_geom_consistency_max_cost,
             "largest forward-backward reprojection error in px for a view to agree");
  parser.Add("PatchMatchStereo.filter", &filter,
             "drop low-confidence pixels, pixels at the ends of the depth range and (with "
             "geom_consistency) pixels the other views' maps disagree with; 0 keeps every "
             "estimate, the geometric pass still estimating with the sources' maps as a prior");
  parser.Add("config_path", &config_path,
             "patch-match.cfg to use instead of stereo/patch-match.cfg (as colmap's)");
  parser.AddSection("OrientationStereo", &options);
  parser.AddSection("SourceViews", &source_options);
  parser.AddSection("OrientationField", &field_options,
                    OrientationStereoOptions::FieldOptionsSetHere());
  parser.AddSection("OpenCL", &opencl_options);
  const std::string kPatchMatchOnly = "PatchMatch-specific; orientation stereo has no such setting";
  for (const char* name :
       {"PatchMatchStereo.window_radius", "PatchMatchStereo.window_step",
        "PatchMatchStereo.sigma_spatial", "PatchMatchStereo.sigma_color",
        "PatchMatchStereo.num_samples", "PatchMatchStereo.ncc_sigma",
        "PatchMatchStereo.incident_angle_sigma", "PatchMatchStereo.num_iterations",
        "PatchMatchStereo.filter_min_ncc", "PatchMatchStereo.write_consistency_graph"}) {
    parser.AddIgnored(name, kPatchMatchOnly);
  }
  parser.AddIgnored("PatchMatchStereo.geom_consistency_regularizer",
                    "the prior's weight is relative to the orientation cost's range here: "
                    "--OrientationStereo.geom_prior_weight");
  parser.AddIgnored("PatchMatchStereo.gpu_index", "use --OpenCL.device to pick the device");
  parser.AddIgnored("PatchMatchStereo.cache_size", "views are cached by count, not size");
  parser.AddIgnored("PatchMatchStereo.allow_missing_files",
                    "a view whose sources have no maps yet gets an unfiltered .geometric map, "
                    "with a warning");
  parser.AddIgnored("pmvs_option_name", "only --workspace_format COLMAP is supported");
  // The options colmap gives every command.
  parser.AddProjectPath({"PatchMatchStereo"});
  parser.AddIgnored("random_seed", "the orientation stereo draws no random numbers");
  parser.AddIgnored("log_to_stderr", "hairmvs logs to stderr always");
  parser.AddIgnored("log_level", "hairmvs logs warnings and errors always");
  if (!parser.Parse(argc, argv)) return 0;
  // Any case, as colmap takes it.
  THROW_IF(ToLower(workspace_format) != "colmap",
           "--workspace_format " << workspace_format << " is not supported (only COLMAP)");
  THROW_IF(parser.WasGiven("config_path") && !parser.FromProjectFile("config_path") &&
               parser.WasGiven("SourceViews.config_path"),
           "hairmvs patch_match_stereo: --config_path and --SourceViews.config_path set the "
           "same file: give one or the other");
  if (parser.WasGiven("config_path") && !parser.WasGiven("SourceViews.config_path")) {
    source_options.config_path = config_path;
  }
  // colmap's options and the fields they set: applied where given, and named in the error
  // when a value they set is refused. `colmap_default`: colmap's default where hairmvs's own
  // differs on purpose (OrientationStereoOptions says why), NaN elsewhere.
  struct MappedOption {
    const char* colmap_name;
    const char* section;  // of the hairmvs option it sets: <section>.<field>
    const char* field;
    double value;  // as given
    double colmap_default;
    std::function<void()> apply;
  };
  constexpr double kSame = std::numeric_limits<double>::quiet_NaN();
  const std::vector<MappedOption> mapped = {
      {"PatchMatchStereo.max_image_size", "OrientationStereo", "max_image_size",
       static_cast<double>(max_image_size), kSame,
       [&] { options.max_image_size = max_image_size; }},
      {"PatchMatchStereo.depth_min", "OrientationStereo", "depth_min", depth_min, kSame,
       [&] { options.depth_min = depth_min; }},
      {"PatchMatchStereo.depth_max", "OrientationStereo", "depth_max", depth_max, kSame,
       [&] { options.depth_max = depth_max; }},
      {"PatchMatchStereo.min_triangulation_angle", "SourceViews", "min_triangulation_angle_deg",
       min_triangulation_angle, kSame,
       [&] { source_options.min_triangulation_angle_deg = min_triangulation_angle; }},
      {"PatchMatchStereo.geom_consistency", "OrientationStereo", "geom_consistency",
       static_cast<double>(geom_consistency), kSame,
       [&] { options.geom_consistency = geom_consistency; }},
      {"PatchMatchStereo.geom_consistency_max_cost", "OrientationStereo",
       "geom_prior_max_error_px", geom_consistency_max_cost, 3,
       [&] { options.geom_prior_max_error_px = geom_consistency_max_cost; }},
      {"PatchMatchStereo.filter_min_num_consistent", "OrientationStereo",
       "geom_consistency_min_views", static_cast<double>(filter_min_num_consistent), 2,
       [&] { options.geom_consistency_min_views = filter_min_num_consistent; }},
      {"PatchMatchStereo.filter_geom_consistency_max_cost", "OrientationStereo",
       "geom_consistency_max_error_px", filter_geom_consistency_max_cost, 1,
       [&] { options.geom_consistency_max_error_px = filter_geom_consistency_max_cost; }},
      {"PatchMatchStereo.filter_min_triangulation_angle", "OrientationStereo",
       "geom_consistency_min_triangulation_angle_deg", filter_min_triangulation_angle, kSame,
       [&] {
         options.geom_consistency_min_triangulation_angle_deg = filter_min_triangulation_angle;
       }},
  };
  // Each colmap option given (on the command line or in a project file) applies, except:
  // - a project file that colmap wrote lists every option, most at colmap's defaults: where
  //   hairmvs's differ on purpose, colmap's from the file are left to them (given on the
  //   command line they apply);
  // - the command line wins over the file: a file's value is not applied over the hairmvs
  //   option it sets when that option is given;
  // - both given on the command line is an error: which one was meant is not ours to guess.
  std::vector<std::string> left_to_hairmvs, overridden;
  for (const MappedOption& option : mapped) {
    if (!parser.WasGiven(option.colmap_name)) continue;
    const bool from_file = parser.FromProjectFile(option.colmap_name);
    const std::string own = std::string(option.section) + "." + option.field;
    THROW_IF(!from_file && parser.WasGiven(own) && !parser.FromProjectFile(own),
             "hairmvs patch_match_stereo: --" << option.colmap_name << " and --" << own
                                             << " set the same option: give one or the other");
    if (from_file && option.value == option.colmap_default) {
      left_to_hairmvs.push_back(option.colmap_name);
    } else if (from_file && parser.WasGiven(own)) {
      overridden.push_back(std::string(option.colmap_name) + " (--" + own + " given)");
    } else {
      option.apply();
    }
  }
  if (!left_to_hairmvs.empty()) {
    LOG(INFO) << "the project file's " << JoinStrings(left_to_hairmvs, ", ")
              << " are colmap's defaults: not applied, hairmvs's own apply (give them on the "
                 "command line to override)";
  }
  if (!overridden.empty()) {
    LOG(INFO) << "the project file's " << JoinStrings(overridden, ", ")
              << ": not applied, the command line's option wins";
  }
  // The geometric pass alone redoes the .geometric maps that exist: colmap's resume does not
  // apply to it (OrientationStereoOptions::skip_existing), unless asked for.
  if (options.geom_consistency_only && !parser.WasGiven("OrientationStereo.skip_existing")) {
    options.skip_existing = false;
  }
  // colmap takes the range as given only when both bounds are >= 0; hairmvs takes each bound
  // > 0 as given and computes the others. A script written for colmap may rely on its rule.
  if (depth_min == 0 || depth_max == 0) {
    LOG(WARNING) << "--PatchMatchStereo.depth_min " << depth_min << ", depth_max " << depth_max
                 << ": a bound of 0 is no depth; hairmvs computes it, where colmap would take "
                    "it as given (with the other >= 0)";
  } else if ((depth_min < 0) != (depth_max < 0)) {
    LOG(WARNING) << "one depth bound given (--PatchMatchStereo.depth_min " << depth_min
                 << ", depth_max " << depth_max << "): colmap would compute both from the "
                 << "sparse points; hairmvs keeps the one given and computes the other";
  }
  // As colmap's: without its geometric pass the maps are named .photometric.
  if (!parser.WasGiven("OrientationStereo.single_pass_type")) {
    options.single_pass_type = options.geom_consistency ? "geometric" : "photometric";
  }
  // As colmap's filter 0: every estimate is kept; with geom_consistency the geometric pass still
  // estimates each view again with its sources' maps as a prior.
  if (!filter) {
    // What filter 0 turns off, given explicitly as well, would be silently overridden: hairmvs's
    // own options are refused; colmap's filter_min_num_consistent is ignored, as colmap does,
    // with a warning (a script written for colmap may pass every option).
    for (const char* filtering :
         {"OrientationStereo.filter_range_ends", "OrientationStereo.min_confidence",
          "OrientationStereo.geom_consistency_min_views"}) {
      THROW_IF(parser.WasGiven(filtering),
               "hairmvs patch_match_stereo: --PatchMatchStereo.filter 0"
                   << (parser.FromProjectFile("PatchMatchStereo.filter") ? " (project file)"
                                                                         : "")
                   << " keeps every estimate; --" << filtering
                   << " filters them: give one or the other");
    }
    // A project file lists the option whatever its filter says: no warning for that.
    if (parser.WasGiven("PatchMatchStereo.filter_min_num_consistent") &&
        !parser.FromProjectFile("PatchMatchStereo.filter_min_num_consistent")) {
      LOG(WARNING) << "--PatchMatchStereo.filter_min_num_consistent is ignored with "
                      "--PatchMatchStereo.filter 0, as colmap ignores it";
    }
    options.filter_range_ends = false;
    options.min_confidence = 0;
    options.geom_consistency_min_views = 0;
  }
  std::string options_error;
  if (!options.Check(&options_error) || !source_options.Check(&options_error)) {
    for (const MappedOption& option : mapped) {
      // Check()'s messages begin with the field and a space ("max_image_size must be ..."):
      // the space keeps geom_consistency from matching geom_consistency_min_views.
      if (parser.WasGiven(option.colmap_name) &&
          options_error.find(std::string(option.field) + " ") != std::string::npos) {
        options_error += std::string(" (") + option.field + " is set by --" +
                         option.colmap_name + ")";
      }
    }
    HAIRMVS_THROW("hairmvs patch_match_stereo: invalid options: " << options_error);
  }
  std::string error;
  THROW_IF(!opencl_options.Check(&error), "invalid --OpenCL options: " << error);
  StageTimings timings;
  const OrientationStereoResult result =
      RunOrientationStereo(workspace_path, {}, options, &timings, opencl_options.device,
                           &source_options, &field_options);
  PrintSummary(result, timings);
  return 0;
}

}  // namespace

HAIRMVS_REGISTER_COMMAND("orientation_stereo", RunOrientationStereoCommand,
                         "depth maps from orientation fields (paper Section 3)");
HAIRMVS_REGISTER_COMMAND("patch_match_stereo", RunPatchMatchStereoCommand,
                         "drop-in for colmap patch_match_stereo (orientation stereo)");

}  // namespace hairmvs
