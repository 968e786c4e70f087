// hairmvs opencl_devices / orientation_fields: the OpenCL devices, and the orientation fields
// of a workspace's images (paper Section 2).

#include <cstdio>
#include <string>

#include "hairmvs/orientation_fields.h"
#include "src/cli/command_registry.h"
#include "src/core/logging.h"
#include "src/core/option_parser.h"
#include "src/core/timer.h"
#include "src/opencl/opencl_context.h"
#include "src/opencl/opencl_options.h"

namespace hairmvs {
namespace {

int RunOpenCLDevices(int argc, char** argv) {
  OpenCLOptions opencl_options;
  OptionParser parser("opencl_devices",
                      "Lists the OpenCL platforms and devices (the index is what --OpenCL.device "
                      "takes) and which one a command would use.");
  parser.AddSection("OpenCL", &opencl_options);
  if (!parser.Parse(argc, argv)) return 0;
  std::printf("%s", OpenCLDevicesTable(ListOpenCLDevices()).c_str());
  const auto context = opencl_options.CreateContext();
  std::printf("Selected (--OpenCL.device '%s'): %s / %s\n", opencl_options.device.c_str(),
              context->PlatformName().c_str(), context->DeviceName().c_str());
  return 0;
}

int RunOrientationFieldsCommand(int argc, char** argv) {
  std::string workspace_path;
  OrientationFieldsRunOptions run_options;
  OrientationFieldOptions options;
  OpenCLOptions opencl_options;
  bool timing = true;
  OptionParser parser(
      "orientation_fields",
      "Computes the orientation field of each image (180-filter bank, 3 levels; Luo et al. "
      "2012, Section 2) and writes stereo/orientation_maps/<image name>.l<k>.bin (2-channel "
      "Mat: Re O, Im O) with <image name>.provenance.txt (its image, mask and filter options: the "
      "stereo reuses the fields only while these hold), and with --write_png 1 a picture per "
      "level (hue = strand angle, brightness = confidence).");
  parser.Add("workspace_path", &workspace_path, "COLMAP dense workspace", true);
  parser.Add("image_names", &run_options.image_names, "comma-separated names (default: all)");
  parser.Add("mask_path", &run_options.mask_path,
             "masks folder (<image name>.png, 0 = excluded; default: <workspace>/masks if any)");
  parser.Add("write_png", &run_options.write_png, "also write <...>.l<k>.png pictures");
  parser.Add("max_image_size", &run_options.max_image_size,
             "larger image side at most this, as the stereo's same max_image_size reads them "
             "(-1: full size)");
  parser.Add("skip_up_to_date", &run_options.skip_up_to_date,
             "keep the images whose cached fields' provenance holds (0: compute all again)");
  parser.Add("timing", &timing, "print the per-stage timing table and the peak memory");
  parser.AddSection("OrientationField", &options);
  parser.AddSection("OpenCL", &opencl_options);
  if (!parser.Parse(argc, argv)) return 0;
  std::string error;
  THROW_IF(!options.Check(&error), "invalid --OrientationField option: " << error);
  THROW_IF(!opencl_options.Check(&error), "invalid --OpenCL option: " << error);
  run_options.opencl_device = opencl_options.device;
  StageTimings timings;
  const OrientationFieldsResult result =
      hairmvs::RunOrientationFields(workspace_path, options, run_options, &timings);
  std::printf("%s\n", result.BriefReport().c_str());
  if (timing) std::printf("%s", RunSummary(timings).c_str());
  return 0;
}

}  // namespace

HAIRMVS_REGISTER_COMMAND("opencl_devices", RunOpenCLDevices,
                         "list OpenCL platforms and devices (--OpenCL.device takes the index)");
HAIRMVS_REGISTER_COMMAND("orientation_fields", RunOrientationFieldsCommand,
                         "orientation fields of a workspace's images (3 levels, 180 filters)");

}  // namespace hairmvs
