// hairmvs synthesize: a synthetic hair data set with exact ground truth, in the layout of the
// shared data sets (a COLMAP dense workspace under <output_path>/dense, ground truth under
// <output_path>/gt).

#include <cstdio>

#include "hairmvs/synthesize.h"
#include "src/cli/command_registry.h"
#include "src/core/option_parser.h"
#include "src/core/timer.h"

namespace hairmvs {
namespace {

int RunSynthesizeCommand(int argc, char** argv) {
  SynthesizeOptions options;
  OptionParser parser("synthesize",
                      "Renders procedural hair on a head proxy from a camera rig and writes a "
                      "COLMAP dense workspace (dense/) with exact ground truth (gt/).");
  // Plain --name options (not --Section.name): this command has a single option set.
  options.ForEachField([&parser](const char* name, auto* value, const char* help) {
    parser.Add(name, value, help, std::string(name) == "output_path");
  });
  if (!parser.Parse(argc, argv)) return 0;
  const SynthesizeResult result = RunSynthesize(options);
  StageTimings timings;
  timings.Add("hair", result.seconds_hair);
  timings.Add("render", result.seconds_render);
  timings.Add("write", result.seconds_write);
  std::printf("%s\n%s", result.BriefReport().c_str(), RunSummary(timings).c_str());
  return 0;
}

}  // namespace

HAIRMVS_REGISTER_COMMAND("synthesize", RunSynthesizeCommand,
                         "render a synthetic hair data set with exact ground truth");

}  // namespace hairmvs
