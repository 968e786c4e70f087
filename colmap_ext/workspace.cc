#include "colmap_ext/workspace.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace fs = std::filesystem;

namespace hairmvs {

namespace {

// The width and height a PNG's header states (its IHDR chunk), without decoding it; false for a
// file that is no PNG or too short to say.
bool PngSize(const std::string& path, int* width, int* height) {
  std::ifstream in(path, std::ios::binary);
  unsigned char header[24];
  if (!in.read(reinterpret_cast<char*>(header), sizeof(header))) return false;
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (std::memcmp(header, kSignature, 8) != 0 || std::memcmp(header + 12, "IHDR", 4) != 0) {
    return false;
  }
  auto big_endian = [&header](int at) {
    return static_cast<int>((static_cast<uint32_t>(header[at]) << 24) |
                            (static_cast<uint32_t>(header[at + 1]) << 16) |
                            (static_cast<uint32_t>(header[at + 2]) << 8) | header[at + 3]);
  };
  *width = big_endian(16);
  *height = big_endian(20);
  return true;
}

// A path inside images/ and stereo/'s folders that names one file one way: relative, no `.`,
// `..` or empty parts. COLMAP takes image names as paths below images/ (sub-folders for a
// rig's cameras), and every output of a view is named after it.
bool IsPlainRelativePath(const std::string& name) {
  if (name.empty() || name.front() == '/') return false;
  for (const std::string& part : SplitString(name, "/")) {
    if (part.empty() || part == "." || part == "..") return false;
  }
  return true;
}

}  // namespace

Workspace Workspace::Read(const std::string& path, const std::string& mask_path,
                          MasksOf masks_of) {
  THROW_IF(path.empty(), "Empty workspace path (--workspace_path)");
  RequireDir(path, "workspace folder");
  const std::string sparse = JoinPaths(path, "sparse");
  const std::string images = JoinPaths(path, "images");
  THROW_IF(ExistsFile(sparse), "The sparse model folder " << sparse << " is a file, not a folder");
  THROW_IF(!ExistsDir(sparse),
           "Missing sparse model: " << sparse
                                    << " (a COLMAP dense workspace as `colmap image_undistorter "
                                       "--output_type COLMAP` writes it)");
  Workspace ws;
  ws.path_ = path;
  ws.model_ = ReadReconstruction(sparse);
  THROW_IF(ws.model_.images.empty(),
           "Empty workspace: the sparse model in " << sparse << " has no images");
  RequireDir(images, "images folder");
  for (uint32_t id : ws.model_.image_order) {
    const Image& image = ws.model_.images.at(id);
    // Two names for one file would overwrite each other's maps; `..` would write outside the
    // workspace.
    THROW_IF(!IsPlainRelativePath(image.name),
             sparse << ": image " << id << " is named '" << image.name
                    << "', which is no path inside " << images
                    << " (it must be relative, without '.', '..' or empty parts): the view's "
                       "outputs are named after it");
    // Unique: ReadReconstruction checks it.
    ws.image_id_by_name_.emplace(image.name, id);
    ws.image_idx_by_name_.emplace(image.name, static_cast<int>(ws.image_idx_by_name_.size()));
    (ExistsFile(JoinPaths(images, image.name)) ? ws.image_names_ : ws.images_without_file_)
        .push_back(image.name);
  }
  // `colmap image_undistorter --image_list_path` writes the whole model but only the listed
  // images, and COLMAP's stereo and fusion then read only those: the others are no views here.
  THROW_IF(ws.image_names_.empty(),
           "None of the " << ws.images_without_file_.size() << " images of the model " << sparse
                          << " is in " << images << " (the first: "
                          << JoinPaths(images, ws.images_without_file_.front()) << ")");
  if (!ws.images_without_file_.empty()) {
    LOG(WARNING) << images << " holds " << ws.image_names_.size() << " of the "
                 << ws.model_.images.size() << " images of the model " << sparse
                 << "; the others (" << JoinFirstNames(ws.images_without_file_)
                 << ") are neither estimated nor source views, as after `colmap "
                    "image_undistorter --image_list_path`";
  }
  if (!mask_path.empty()) {
    THROW_IF(!ExistsDir(mask_path), "Missing mask folder (the mask_path given): " << mask_path);
    ws.mask_path_ = mask_path;
  } else if (Exists(JoinPaths(path, "masks"))) {  // a file there is no "no masks"
    RequireDir(JoinPaths(path, "masks"), "mask folder");
    ws.mask_path_ = JoinPaths(path, "masks");
  }
  // Each image's mask looked up once: those without one, and those a few percent off their
  // image's size, which is likely drawn on the photo: the undistorter shrinks or grows both
  // sides of a photo alike for radial distortion, so ReadMask takes such a mask for a scaled
  // copy, misplaced by pixels towards the edges. Said, not refused: a mask resized on purpose
  // is read as one. (The header alone: PNG masks, as COLMAP names them.)
  std::vector<std::string> unmasked, near_size;
  for (const std::string& name : ws.mask_path_.empty() ? std::vector<std::string>()
                                                        : ws.image_names_) {
    const std::string mask = ws.MaskPath(name);
    int width = 0, height = 0;
    if (mask.empty()) {
      unmasked.push_back(name);
    } else if (masks_of == MasksOf::kImages && PngSize(mask, &width, &height)) {
      const Camera& camera = ws.model_.cameras.at(ws.ImageByName(name).camera_id);
      const double scale = static_cast<double>(width) / camera.width;
      // Only those read as scaled copies: one of another aspect ratio is refused when read.
      if ((width != static_cast<int>(camera.width) ||
           height != static_cast<int>(camera.height)) &&
          scale > 0.9 && scale < 1.1 &&
          IsScaledCopy(width, height, static_cast<int>(camera.width),
                       static_cast<int>(camera.height))) {
        std::ostringstream line;
        line << name << " (" << width << " x " << height << " for " << camera.width << " x "
             << camera.height << ")";
        near_size.push_back(line.str());
      }
    }
  }
  if (!unmasked.empty() && unmasked.size() == ws.image_names_.size()) {
    // Files there, but none named for an image: a naming mistake (the image's stem, say), not
    // a choice to match the whole scene. And a folder given for the masks that holds none is a
    // wrong folder; the workspace's own masks/ left empty is taken as no masks (warned about
    // below).
    std::optional<std::string> first_image_file;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(ws.mask_path_, ec)) {
      const std::string extension = ToLower(entry.path().extension().string());
      if (entry.is_regular_file(ec) && entry.path().filename().string()[0] != '.' &&
          (extension == ".png" || extension == ".jpg" || extension == ".jpeg" ||
           extension == ".bmp" || extension == ".tif" || extension == ".tiff")) {
        first_image_file = entry.path().filename().string();
        break;
      }
    }
    const bool holds_images = first_image_file.has_value();
    THROW_IF(holds_images || !mask_path.empty(),
             "No mask in " << ws.mask_path_ << (holds_images ? "" : " (the mask folder given)")
                           << " belongs to an image of the workspace: it holds "
                           << first_image_file.value_or("no image file")
                           << (holds_images ? ", but" : ";") << " the mask of the image "
                           << ws.image_names_.front() << " is "
                           << JoinPaths(ws.mask_path_, ws.image_names_.front() + ".png")
                           << " (COLMAP's naming: <image name>.png)");
  }
  if (!unmasked.empty()) {
    // COLMAP skips a missing mask silently; here a view without one lets its background into
    // the depth range and the depth map, so say which.
    LOG(WARNING) << ws.mask_path_ << ": no mask for " << unmasked.size() << " of "
                 << ws.image_names_.size() << " images (" << JoinFirstNames(unmasked)
                 << "; expected "
                 << JoinPaths(ws.mask_path_, "<image name>.png")
                 << "): they are processed without a mask";
  }
  if (!near_size.empty()) {
    LOG(WARNING) << ws.mask_path_ << ": " << near_size.size() << " mask(s) a few percent off "
                 << "their image's size, " << near_size.front()
                 << (near_size.size() > 1 ? ", ..." : "")
                 << ": drawn on the photos before colmap image_undistorter? They are read as "
                    "scaled copies, which such masks are not (hairmvs undistort_masks undistorts "
                    "masks drawn on the photos)";
  }
  return ws;
}

std::vector<std::string> Workspace::ImagesWithoutMask() const {
  std::vector<std::string> names;
  if (mask_path_.empty()) return names;
  for (const std::string& name : image_names_) {
    if (MaskPath(name).empty()) names.push_back(name);
  }
  return names;
}

int Workspace::ImageIdx(const std::string& name, const std::string& given_by) const {
  const auto it = image_idx_by_name_.find(name);
  THROW_IF(it == image_idx_by_name_.end(),
           "Image with name `" << name << "`" << (given_by.empty() ? "" : " (" + given_by + ")")
                               << " does not exist in workspace " << path_);
  return it->second;
}

bool Workspace::HasImageFile(const std::string& name) const {
  return std::find(images_without_file_.begin(), images_without_file_.end(), name) ==
             images_without_file_.end() &&
         image_idx_by_name_.count(name) > 0;
}

void Workspace::RequireView(const std::string& name, const std::string& given_by) const {
  ImageIdx(name, given_by);
  THROW_IF(!HasImageFile(name),
           "Image `" << name << "`" << (given_by.empty() ? "" : " (" + given_by + ")")
                     << " is in the model of " << path_
                     << " but not in its images folder: " << ImagePath(name));
}

std::vector<std::string> Workspace::SelectImages(
    const std::vector<std::string>& requested) const {
  if (requested.empty()) return image_names_;
  std::vector<int> seen;
  for (const std::string& name : requested) {
    RequireView(name, "--image_names");
    const int idx = ImageIdx(name, "--image_names");
    THROW_IF(std::find(seen.begin(), seen.end(), idx) != seen.end(),
             "Image `" << name << "` is given twice (--image_names)");
    seen.push_back(idx);
  }
  return requested;
}

const Image& Workspace::ImageByName(const std::string& name) const {
  const auto it = image_id_by_name_.find(name);
  THROW_IF(it == image_id_by_name_.end(),
           "Image with name `" << name << "` does not exist in workspace " << path_);
  return model_.images.at(it->second);
}

const Camera& Workspace::CameraOf(const std::string& name) const {
  const Image& image = ImageByName(name);
  const Camera& camera = model_.cameras.at(image.camera_id);
  // Names the model folder: the camera's model is in sparse/, not in the images.
  camera.RequirePinhole("Image " + name + " in " + JoinPaths(path_, "sparse"));
  return camera;
}

void Workspace::RequireUndistortedCameras() const {
  for (const std::string& name : image_names_) CameraOf(name);
}

void Workspace::RequireCameraSize(const std::string& name, int width, int height) const {
  const std::string path = ImagePath(name);
  const Camera& camera = model_.cameras.at(ImageByName(name).camera_id);
  THROW_IF(width != static_cast<int>(camera.width) || height != static_cast<int>(camera.height),
           "Image " << path << " is " << width << " x " << height
                    << " but its camera " << camera.camera_id << " is " << camera.width << " x "
                    << camera.height
                    << ": images/ must be as colmap image_undistorter wrote them (the stereo's "
                       "--OrientationStereo.max_image_size works at a lower resolution without "
                       "resizing them)");
}

std::string Workspace::ImagePathOfCameraSize(const std::string& name) const {
  const std::string path = ImagePath(name);
  int width = 0, height = 0;
  if (PngSize(path, &width, &height)) RequireCameraSize(name, width, height);
  return path;
}

namespace {

FloatMap ResizeArea(const FloatMap& input, int width, int height) {
  if (input.Width() == width && input.Height() == height) return input;
  FloatMap out(width, height, input.Channels());
  for (int c = 0; c < input.Channels(); ++c) {
    cv::Mat src(input.Height(), input.Width(), CV_32F, const_cast<float*>(input.Channel(c)));
    cv::Mat dst(height, width, CV_32F, out.Channel(c));
    cv::resize(src, dst, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  }
  return out;
}

}  // namespace

FloatMap Workspace::AtMaxImageSize(const std::string& name, FloatMap image,
                                   int max_image_size) const {
  RequireCameraSize(name, image.Width(), image.Height());
  if (max_image_size <= 0) return image;
  const StereoCamera camera = ViewCamera(name).AtMaxImageSize(max_image_size);
  return ResizeArea(image, camera.width, camera.height);
}

FloatMap Workspace::ReadViewGray(const std::string& name, int max_image_size) const {
  return AtMaxImageSize(name, ReadImageGray(ImagePathOfCameraSize(name)), max_image_size);
}

FloatMap Workspace::ReadViewRgb(const std::string& name, int max_image_size) const {
  return AtMaxImageSize(name, ReadImageRgb(ImagePathOfCameraSize(name)), max_image_size);
}

std::string Workspace::ImagePath(const std::string& name) const {
  return JoinPaths(path_, "images", name);
}

std::string Workspace::MaskPath(const std::string& name) const {
  if (mask_path_.empty()) return "";
  // COLMAP's fusion naming: <mask_path>/<image name>.png; 3.12+ also accepts the name itself
  // when it already ends in .png.
  const std::string path = JoinPaths(mask_path_, name + ".png");
  if (ExistsFile(path)) return path;
  if (name.size() > 4 && name.compare(name.size() - 4, 4, ".png") == 0) {
    const std::string same = JoinPaths(mask_path_, name);
    if (ExistsFile(same)) return same;
  }
  return "";
}

StereoCamera Workspace::ViewCamera(const std::string& name) const {
  const Camera& camera = CameraOf(name);
  const Image& image = ImageByName(name);
  StereoCamera view;
  view.K = camera.CalibrationMatrix();
  view.R = image.R();
  view.t = image.t();
  view.width = static_cast<int>(camera.width);
  view.height = static_cast<int>(camera.height);
  return view;
}

std::string Workspace::StereoPath() const { return JoinPaths(path_, "stereo"); }

std::string Workspace::DepthMapPath(const std::string& name, const std::string& type) const {
  THROW_IF(type != "geometric" && type != "photometric",
           "Unknown depth map type '" << type << "' (geometric or photometric)");
  return JoinPaths(StereoPath(), "depth_maps", name + "." + type + ".bin");
}

std::string Workspace::NormalMapPath(const std::string& name, const std::string& type) const {
  THROW_IF(type != "geometric" && type != "photometric",
           "Unknown normal map type '" << type << "' (geometric or photometric)");
  return JoinPaths(StereoPath(), "normal_maps", name + "." + type + ".bin");
}

// hairmvs's own per-view maps, named like COLMAP's: stereo/<kind>_maps/<image name>.<...>.bin.
std::string Workspace::ConfidenceMapPath(const std::string& name) const {
  return JoinPaths(StereoPath(), "confidence_maps", name + ".bin");
}

std::string Workspace::CostVolumePath(const std::string& name) const {
  return JoinPaths(StereoPath(), "cost_volumes", name + ".coarse.bin");
}

std::string Workspace::CostVolumeDepthsPath(const std::string& name) const {
  return JoinPaths(StereoPath(), "cost_volumes", name + ".coarse.depths.txt");
}

std::string Workspace::OrientationMapPath(const std::string& name, int level) const {
  CHECK_GE(level, 0);
  return JoinPaths(StereoPath(), "orientation_maps",
                   name + ".l" + std::to_string(level) + ".bin");
}

std::string Workspace::OrientationMapProvenancePath(const std::string& name) const {
  return JoinPaths(StereoPath(), "orientation_maps", name + ".provenance.txt");
}

// ---------------------------------------------------------------------------------------------
// Images.

namespace {

// Whether a JPEG stream reaches its end-of-image marker. libjpeg decodes a truncated file
// without an error, filling what is missing with grey (OpenCV only prints "Premature end of
// JPEG file"). The walk follows the stream's own structure from the start-of-image marker:
// length-prefixed segments (an EXIF thumbnail lies inside one) are skipped whole, each scan's
// entropy-coded data runs to the next marker that is not a restart marker (0xFF is stuffed as
// FF 00 there), and the first end-of-image marker at the top level ends the image. Bytes a
// camera appends after it (a motion photo's video, a maker trailer) are never read, whatever
// markers they hold.
bool JpegIsComplete(const std::string& bytes) {
  const auto at = [&](size_t i) { return static_cast<uint8_t>(bytes[i]); };
  const auto is_restart = [](uint8_t marker) { return marker >= 0xD0 && marker <= 0xD7; };
  size_t i = 2;  // after FF D8
  while (i + 1 < bytes.size()) {
    if (at(i) != 0xFF) {  // extraneous bytes before a marker, which libjpeg skips too
      ++i;
      continue;
    }
    const uint8_t marker = at(i + 1);
    if (marker == 0xFF) {  // fill byte before a marker
      ++i;
      continue;
    }
    if (marker == 0xD9) return true;
    if (marker == 0x01 || is_restart(marker)) {  // TEM, RSTn: no length
      i += 2;
      continue;
    }
    if (i + 3 >= bytes.size()) return false;
    const size_t length = (size_t{at(i + 2)} << 8) | at(i + 3);  // includes its own 2 bytes
    if (length < 2) return false;
    i += 2 + length;
    if (marker != 0xDA) continue;
    // Entropy-coded data of the scan: up to the next FF that is neither FF 00 nor a restart.
    while (i + 1 < bytes.size()) {
      const uint8_t next = at(i + 1);
      if (at(i) == 0xFF && next != 0x00 && next != 0xFF && !is_restart(next)) break;
      ++i;
    }
  }
  return false;
}

cv::Mat ReadUnchanged(const std::string& path, const char* what) {
  RequireFile(path, what);
  const std::string bytes = ReadTextFile(path);
  cv::Mat image;
  if (!bytes.empty()) {
    try {
      image = cv::imdecode(cv::Mat(1, static_cast<int>(bytes.size()), CV_8U,
                                   const_cast<char*>(bytes.data())),
                           cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception& e) {  // e.g. more pixels than OpenCV decodes (2^30)
      HAIRMVS_THROW("Cannot decode " << what << " " << path << " (" << bytes.size()
                                     << " bytes): OpenCV refused it: " << e.err);
    }
  }
  THROW_IF(image.empty(), "Cannot decode " << what << " " << path << " (" << bytes.size()
                                           << " bytes): truncated, or not an image format "
                                              "OpenCV reads");
  const bool jpeg = bytes.size() >= 2 && static_cast<uint8_t>(bytes[0]) == 0xFF &&
                    static_cast<uint8_t>(bytes[1]) == 0xD8;
  THROW_IF(jpeg && !JpegIsComplete(bytes),
           "Truncated " << what << " " << path << " (" << bytes.size()
                        << " bytes): the JPEG data ends before its end-of-image marker");
  return image;
}

// To float in [0, 1] from 8- or 16-bit (or float) data.
cv::Mat ToUnitFloat(const cv::Mat& image, const std::string& path) {
  cv::Mat out;
  switch (image.depth()) {
    case CV_8U: image.convertTo(out, CV_32F, 1.0 / 255.0); break;
    case CV_16U: image.convertTo(out, CV_32F, 1.0 / 65535.0); break;
    case CV_32F: {
      // Float pixels are taken as they are: only [0, 1] means what 8 and 16 bits scaled do (a
      // float TIFF holding 0-255 would read 255 times too bright).
      double lowest = 0, highest = 0;
      cv::minMaxLoc(image.reshape(1), &lowest, &highest);
      THROW_IF(!std::isfinite(lowest) || !std::isfinite(highest) || lowest < 0 ||
                   highest > 1.0 + 1e-6,
               "Float image " << path << " holds values from " << lowest << " to " << highest
                              << ", not in [0, 1]: write it with 8 or 16 bits per channel, or "
                                 "scaled to [0, 1]");
      out = image;
      break;
    }
    default: HAIRMVS_THROW("Unsupported pixel depth in image " << path);
  }
  return out;
}

FloatMap FromPlanes(const std::vector<cv::Mat>& planes) {
  CHECK(!planes.empty());
  FloatMap map(planes[0].cols, planes[0].rows, static_cast<int>(planes.size()));
  for (size_t c = 0; c < planes.size(); ++c) {
    for (int r = 0; r < planes[c].rows; ++r) {
      const float* row = planes[c].ptr<float>(r);
      std::copy(row, row + planes[c].cols, map.Channel(static_cast<int>(c)) + r * map.Width());
    }
  }
  return map;
}

// OpenCV order is BGR(A); returns R, G, B float planes.
std::vector<cv::Mat> RgbPlanes(const cv::Mat& image, const std::string& path) {
  const cv::Mat f = ToUnitFloat(image, path);
  std::vector<cv::Mat> channels;
  cv::split(f, channels);
  if (channels.size() == 1 || channels.size() == 2) {  // grey (+ alpha)
    return {channels[0], channels[0], channels[0]};
  }
  THROW_IF(channels.size() != 3 && channels.size() != 4,
           "Unsupported number of channels (" << channels.size() << ") in image " << path);
  return {channels[2], channels[1], channels[0]};
}

}  // namespace

FloatMap ReadImageGray(const std::string& path) {
  const cv::Mat image = ReadUnchanged(path, "image");
  const std::vector<cv::Mat> rgb = RgbPlanes(image, path);
  // BT.601 luma, as cv::cvtColor(BGR2GRAY) and COLMAP's Bitmap do.
  if (image.channels() <= 2) return FromPlanes({rgb[0]});
  const cv::Mat gray = 0.299f * rgb[0] + 0.587f * rgb[1] + 0.114f * rgb[2];
  return FromPlanes({gray});
}

FloatMap ReadImageRgb(const std::string& path) {
  const cv::Mat image = ReadUnchanged(path, "image");
  return FromPlanes(RgbPlanes(image, path));
}

FloatMap ReadMask(const std::string& path, int width, int height) {
  CHECK_GT(width, 0);
  CHECK_GT(height, 0);
  if (path.empty()) return FloatMap(width, height, 1, 1.0f);
  // A mask of another size is taken as the same picture at another scale (COLMAP's fusion
  // rescales masks too). Another aspect ratio cannot line up with the image, e.g. a mask drawn
  // on a photo before colmap image_undistorter changed its size: an error, not a silently
  // shifted mask. One pixel of rounding is allowed each way. Checked from a PNG's header
  // before it is decoded too (a huge wrong mask takes gigabytes to decode).
  const auto require_scaled_copy = [&](int mask_width, int mask_height) {
    THROW_IF(!IsScaledCopy(mask_width, mask_height, width, height),
             "Mask " << path << " is " << mask_width << " x " << mask_height
                     << ", another aspect ratio than its image's (read at " << width << " x "
                     << height << ")"
                     << (IsScaledCopy(mask_height, mask_width, width, height)
                             ? ", its width and height swapped (turned by an EXIF orientation "
                               "that an editor applied? COLMAP ignores the tag)"
                             : "")
                     << ": a mask is drawn on its own image (the workspace's "
                        "images/ as colmap image_undistorter wrote them, or the photo for "
                        "undistort_masks), or is a scaled copy of one");
  };
  int header_width = 0, header_height = 0;
  if (PngSize(path, &header_width, &header_height)) {
    require_scaled_copy(header_width, header_height);
  }
  const cv::Mat image = ReadUnchanged(path, "mask");
  std::vector<cv::Mat> channels;
  cv::split(image, channels);
  // Grey value 0 excludes (COLMAP reads masks as grayscale); for colour masks any non-zero
  // colour channel keeps the pixel.
  cv::Mat keep = cv::Mat::zeros(image.rows, image.cols, CV_8U);
  int num_colour = static_cast<int>(channels.size());
  if (num_colour == 2 || num_colour == 4) --num_colour;  // alpha does not count
  for (int c = 0; c < num_colour; ++c) {
    cv::Mat nonzero = channels[c] != 0;
    cv::bitwise_or(keep, nonzero, keep);
  }
  if (num_colour < static_cast<int>(channels.size())) {
    // A cut-out (a background-removal tool's PNG: the photo in colour, the mask as alpha)
    // keeps by its colour, as COLMAP reads it, the pixels its alpha makes transparent. Where
    // more than an antialiased rim is so, the file's meaning is not COLMAP's: refused. (An
    // opaque alpha, as many editors write with a black and white mask, is no such case.)
    const cv::Mat transparent = channels.back() == 0;
    cv::Mat kept_but_transparent;
    cv::bitwise_and(keep, transparent, kept_but_transparent);
    const double fraction =
        static_cast<double>(cv::countNonZero(kept_but_transparent)) / keep.total();
    THROW_IF(fraction > 0.01,
             "Mask " << path << ": " << std::lround(100 * fraction) << "% of its pixels are "
                     << "transparent in its alpha channel but kept by their colour, as COLMAP "
                     << "reads a mask (a grey image, 0 = excluded, alpha ignored): write it as "
                        "a grey PNG, 0 where excluded and 255 where kept (e.g. the alpha "
                        "channel alone)");
  }
  const int num_kept = cv::countNonZero(keep);
  THROW_IF(num_kept == 0, "Mask " << path << " excludes every pixel (all zero at " << keep.cols
                                  << "x" << keep.rows << ")");
  if (keep.cols != width || keep.rows != height) {
    require_scaled_copy(keep.cols, keep.rows);
    cv::Mat resized;
    cv::resize(keep, resized, cv::Size(width, height), 0, 0, cv::INTER_NEAREST);
    keep = resized;
    THROW_IF(cv::countNonZero(keep) == 0,
             "Mask " << path << " keeps " << num_kept << " pixel(s) at its own size but none "
                     << "once scaled to " << width << "x" << height
                     << " (a smaller max_image_size than the mask's thinnest parts allow)");
  }
  FloatMap map(width, height, 1, 0.0f);
  for (int r = 0; r < height; ++r) {
    const uint8_t* row = keep.ptr<uint8_t>(r);
    for (int c = 0; c < width; ++c) map.At(r, c) = row[c] != 0 ? 1.0f : 0.0f;
  }
  return map;
}

void WriteImage(const std::string& path, const FloatMap& image) {
  CHECK(image.Channels() == 1 || image.Channels() == 3) << image.Channels();
  std::vector<cv::Mat> planes;
  // OpenCV wants B, G, R.
  for (int c = image.Channels() - 1; c >= 0; --c) {
    cv::Mat plane(image.Height(), image.Width(), CV_32F,
                  const_cast<float*>(image.Channel(c)));
    cv::Mat bytes;
    plane.convertTo(bytes, CV_8U, 255.0);  // saturating, rounding
    planes.push_back(bytes);
  }
  cv::Mat merged;
  cv::merge(planes, merged);
  WriteImage(path, merged);
}

void WriteImage(const std::string& path, const cv::Mat& image) {
  WritePathAtomically(path, [&](const std::string& tmp_path) {
    bool written = false;
    try {
      written = cv::imwrite(tmp_path, image);
    } catch (const cv::Exception& e) {  // e.g. an extension OpenCV has no writer for
      HAIRMVS_THROW("Cannot write image " << path << ": " << e.err);
    }
    THROW_IF(!written, "Cannot write image " << path);
  });
}

}  // namespace hairmvs
