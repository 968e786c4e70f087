#pragma once
// A COLMAP dense workspace as `colmap image_undistorter --output_type COLMAP` writes it:
// images/, sparse/ (bin or txt), stereo/ (patch-match.cfg, fusion.cfg, depth_maps/,
// normal_maps/), optional masks (<mask_path>/<image name>.png, 0 = excluded).
// hairmvs adds stereo/orientation_maps/ and stereo/confidence_maps/ in the same naming.

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "colmap_ext/reconstruction.h"
#include "src/core/depth_geometry.h"
#include "src/core/float_map.h"

namespace cv {
class Mat;
}  // namespace cv

namespace hairmvs {

class Workspace {
 public:
  // What the masks of `mask_path` are drawn on: the workspace's images (the stereo's masks) or
  // the photos they were undistorted from (undistort_masks' input, at the photos' sizes, which
  // are not checked against the images').
  enum class MasksOf { kImages, kPhotos };
  // Reads the model of `path`/sparse; its images found under images/ are the workspace's
  // views (those missing are warned about, as `colmap image_undistorter --image_list_path`
  // leaves them; none found is an error). `mask_path` empty: `path`/masks if that folder
  // exists, else no masks. Throws hairmvs::Error naming the file and the problem.
  static Workspace Read(const std::string& path, const std::string& mask_path = "",
                        MasksOf masks_of = MasksOf::kImages);

  const std::string& Path() const { return path_; }
  const Reconstruction& Model() const { return model_; }
  // The views: the names of the model's images that images/ holds, in COLMAP's image_idx order
  // (the order of the records in sparse/images.*).
  const std::vector<std::string>& ImageNames() const { return image_names_; }
  // COLMAP's image_idx of a model image (its record's place in sparse/images.*, counting the
  // images without a file too: what fused.ply.vis refers to). Throws for a name the model lacks,
  // saying where it was given (`given_by`, e.g. an option) if not empty.
  int ImageIdx(const std::string& name, const std::string& given_by = "") const;
  // Whether `name` is one of ImageNames(): in the model and in images/.
  bool HasImageFile(const std::string& name) const;
  // Throws as ImageIdx does, and for a model image that images/ lacks, naming its path.
  void RequireView(const std::string& name, const std::string& given_by = "") const;
  // The views a command works on: `requested` (--image_names) as given, or every view when it
  // is empty. Throws for a name that is no view (RequireView), and for a name given twice (its
  // maps would be computed twice, and it would count as two views).
  std::vector<std::string> SelectImages(const std::vector<std::string>& requested) const;
  const Image& ImageByName(const std::string& name) const;
  // Throws (telling the user to run colmap image_undistorter) unless PINHOLE/SIMPLE_PINHOLE.
  const Camera& CameraOf(const std::string& name) const;
  // Throws, as CameraOf does, unless every image's camera is PINHOLE or SIMPLE_PINHOLE: what
  // the dense stage needs of all the views (any can be a source), checked before any work.
  void RequireUndistortedCameras() const;

  std::string ImagePath(const std::string& name) const;
  // Image `name` in grey / RGB (ReadImageGray / ReadImageRgb of ImagePath). Throws unless it
  // has its camera's size: an image resized or cropped after image_undistorter no longer fits
  // its intrinsics, which would put every depth off. With `max_image_size` (> 0), area-resized
  // to the processing size ViewCamera(name).AtMaxImageSize(max_image_size), as COLMAP's
  // stereo reads it.
  FloatMap ReadViewGray(const std::string& name, int max_image_size = -1) const;
  FloatMap ReadViewRgb(const std::string& name, int max_image_size = -1) const;
  // The camera of image `name` (its intrinsics and pose) on its image's pixel grid; Scaled()
  // carries it to a smaller map's (COLMAP's max_image_size, a coarse grid).
  StereoCamera ViewCamera(const std::string& name) const;
  // The masks folder (`mask_path`, or `path`/masks); "" when the workspace has none.
  const std::string& MaskFolder() const { return mask_path_; }
  // "" when the workspace has no masks or this image has none.
  std::string MaskPath(const std::string& name) const;
  // With a masks folder, the images that have no mask in it (Read warns about them).
  std::vector<std::string> ImagesWithoutMask() const;
  std::string StereoPath() const;
  // type: "geometric" or "photometric".
  std::string DepthMapPath(const std::string& name, const std::string& type = "geometric") const;
  std::string NormalMapPath(const std::string& name, const std::string& type = "geometric") const;
  std::string ConfidenceMapPath(const std::string& name) const;
  // The coarse data term (--OrientationStereo.write_cost_volume) and its labels' depths.
  std::string CostVolumePath(const std::string& name) const;
  std::string CostVolumeDepthsPath(const std::string& name) const;
  std::string OrientationMapPath(const std::string& name, int level) const;
  // What the cached levels of `name` were computed from (src/orientation/orientation_maps.h).
  std::string OrientationMapProvenancePath(const std::string& name) const;

 private:
  // Throws naming ImagePath(name) unless `width` x `height` is its camera's size.
  void RequireCameraSize(const std::string& name, int width, int height) const;
  // ImagePath(name), checked by RequireCameraSize from a PNG's header before it is decoded (an
  // image of another size can take gigabytes to decode only to be refused).
  std::string ImagePathOfCameraSize(const std::string& name) const;
  // `image` (read from ImagePath(name)) checked by RequireCameraSize, then area-resized to
  // the processing size of max_image_size (> 0; as it is otherwise).
  FloatMap AtMaxImageSize(const std::string& name, FloatMap image, int max_image_size) const;

  std::string path_;
  std::string mask_path_;
  Reconstruction model_;
  std::vector<std::string> image_names_;
  std::vector<std::string> images_without_file_;  // model images that images/ lacks
  std::unordered_map<std::string, int> image_idx_by_name_;  // every model image's
  // The model's image_id of each name (ImageByName without a search through the model).
  std::unordered_map<std::string, uint32_t> image_id_by_name_;
};

// Images as float maps, for the dense stages. Throws hairmvs::Error naming the file.
// Grey in [0, 1] (BT.601 luma of 8- or 16-bit images).
FloatMap ReadImageGray(const std::string& path);
// RGB in [0, 1], 3 channels (R, G, B planes).
FloatMap ReadImageRgb(const std::string& path);
// A mask resized to width x height (nearest); 1 = keep, 0 = excluded. An all-zero mask, or
// one of another aspect ratio than width x height (beyond a pixel's rounding), is an error
// naming the file. Returns a map of ones if `path` is empty.
FloatMap ReadMask(const std::string& path, int width, int height);
// Writes a 1- or 3-channel (R, G, B) map with values in [0, 1] as an 8-bit image (format from
// the extension, e.g. .png), atomically. Values are clamped and rounded.
void WriteImage(const std::string& path, const FloatMap& image);
// Writes an OpenCV image (grey or B, G, R, as cv::imwrite takes it) atomically; throws
// hairmvs::Error naming `path` if OpenCV cannot write it.
void WriteImage(const std::string& path, const cv::Mat& image);

}  // namespace hairmvs
