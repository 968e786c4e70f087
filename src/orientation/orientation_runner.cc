// `hairmvs orientation_fields`: the orientation field of every image of a workspace.

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "colmap_ext/mat_io.h"
#include "colmap_ext/workspace.h"
#include "hairmvs/orientation_fields.h"
#include "src/core/depth_geometry.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/progress.h"
#include "src/opencl/opencl_context.h"
#include "src/orientation/orientation_field.h"
#include "src/orientation/orientation_maps.h"

namespace hairmvs {
namespace {

// Hue = strand angle Theta in [0, pi) (OpenCV's 8-bit hue is 0..179 for 0..358 degrees, so
// Theta in degrees maps to the full hue circle, and Theta and Theta + pi look the same);
// brightness = confidence / (its 99th percentile over the valid pixels of this map).
void WriteOrientationPng(const std::string& path, const FloatMap& field) {
  const int w = field.Width(), h = field.Height();
  std::vector<float> confidences;
  for (size_t i = 0; i < field.NumPixels(); ++i) {
    const float c = std::hypot(field.Channel(0)[i], field.Channel(1)[i]);
    if (c > 0) confidences.push_back(c);
  }
  float scale = 1;
  if (!confidences.empty()) {
    const size_t nth = std::min(confidences.size() - 1, confidences.size() * 99 / 100);
    std::nth_element(confidences.begin(), confidences.begin() + nth, confidences.end());
    scale = confidences[nth] > 0 ? 1.0f / confidences[nth] : 1.0f;
  }
  cv::Mat hsv(h, w, CV_8UC3);
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const float re = field.At(r, c, 0), im = field.At(r, c, 1);
      double theta_deg = std::atan2(im, re) * 0.5 * 180.0 / M_PI;  // (-90, 90]
      if (theta_deg < 0) theta_deg += 180;
      const double value = std::min(1.0, static_cast<double>(std::hypot(re, im) * scale));
      hsv.at<cv::Vec3b>(r, c) = cv::Vec3b(static_cast<uint8_t>(std::lround(theta_deg) % 180), 255,
                                          static_cast<uint8_t>(std::lround(255 * value)));
    }
  }
  cv::Mat bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  WriteImage(path, bgr);
}

}  // namespace

std::string OrientationFieldsResult::BriefReport() const {
  std::ostringstream out;
  out << "Orientation fields: " << num_images << " image(s)";
  if (num_up_to_date > 0) out << " (and " << num_up_to_date << " up to date, kept)";
  out << ", " << num_levels << " level(s), "
      << num_files_written << " file(s) written in " << seconds << " s on " << device_name;
  return out.str();
}

OrientationFieldsResult RunOrientationFields(const std::string& workspace_path,
                                             const OrientationFieldOptions& options,
                                             const OrientationFieldsRunOptions& run_options,
                                             StageTimings* timings) {
  Timer total_timer;
  std::string error;
  THROW_IF(!options.Check(&error), "OrientationField options: " << error);
  THROW_IF(!IsValidMaxImageSize(run_options.max_image_size),
           "invalid --max_image_size " << run_options.max_image_size << ": must be > 0 or -1");
  Workspace workspace = [&] {
    ScopedStageTimer timer(timings, "read workspace");
    return Workspace::Read(workspace_path, run_options.mask_path);
  }();
  const std::vector<std::string> names = workspace.SelectImages(run_options.image_names);

  std::shared_ptr<OpenCLContext> context;
  std::unique_ptr<OrientationFieldComputer> computer;
  {
    ScopedStageTimer timer(timings, "OpenCL setup");
    context = OpenCLContext::Create(run_options.opencl_device);
    computer = std::make_unique<OrientationFieldComputer>(context, options);
  }
  computer->SetTimings(timings);

  OrientationFieldsResult result;
  result.num_levels = options.num_levels;
  result.device_name = context->DeviceName();
  Progress progress("orientation_fields", static_cast<int>(names.size()));
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string& name = names[i];
    progress.Start(static_cast<int>(i), name);
    const StereoCamera camera =
        workspace.ViewCamera(name).AtMaxImageSize(run_options.max_image_size);
    const std::string provenance =
        OrientationFieldsProvenance(workspace, name, camera.width, camera.height, options);
    // The cached levels, read and checked against the bytes their provenance recorded, as the
    // stereo reads them: a damaged level is computed again here, not only when the stereo
    // meets it.
    std::optional<std::vector<FloatMap>> cached;
    if (run_options.skip_up_to_date) {
      std::string why_not;
      cached = ReadCachedOrientationFields(workspace, name, provenance, camera,
                                           options.num_levels, &why_not);
      bool pictures = true;
      for (int l = 0; l < options.num_levels && cached && run_options.write_png; ++l) {
        pictures = pictures && ExistsFile(OrientationPicturePath(workspace, name, l));
      }
      if (cached && pictures) {
        progress.Stage("up to date (its provenance holds): kept");
        ++result.num_up_to_date;
        continue;
      }
      if (!why_not.empty()) progress.Stage(why_not + ": computing them again");
    }
    // Checked (and created) only for a view that writes, before its work: fields all up to date
    // in a folder this user may not write to (a shared, read-only workspace) are no error; and
    // only once the device holds, so that a run refused for it leaves no empty folders.
    RequireWritableDir(ParentPath(workspace.OrientationMapPath(name, 0)), "orientation map folder");
    std::vector<FloatMap> levels;
    if (cached) {
      // Only the pictures are missing: drawn from the fields read, not from the filter bank's
      // work done again.
      levels = std::move(*cached);
      progress.Stage("up to date, pictures missing: writing them");
    } else {
      progress.Stage("read image, filter bank");
      levels = ComputeViewOrientationFields(workspace, name, run_options.max_image_size,
                                            computer.get(), timings);
      progress.Stage("write");
      ScopedStageTimer timer(timings, "write");
      WriteOrientationFields(workspace, name, provenance, levels);
      result.num_files_written += static_cast<int>(levels.size()) + 1;
    }
    if (run_options.write_png) {
      ScopedStageTimer timer(timings, "write");
      for (int l = 0; l < static_cast<int>(levels.size()); ++l) {
        WriteOrientationPng(OrientationPicturePath(workspace, name, l), levels[l]);
        ++result.num_files_written;
      }
    }
    ++result.num_images;
  }
  progress.Finish();
  result.seconds = total_timer.ElapsedSeconds();
  return result;
}

}  // namespace hairmvs
