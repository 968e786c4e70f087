#pragma once
// COLMAP's sparse model (cameras, images, points3D), read and written in COLMAP's binary and
// text formats (../shared/design/colmap-formats.md section 4). Records are kept sorted by id;
// `image_order` keeps the order of the records in the files as read, which is COLMAP 3.8's
// image index (image_idx) for .vis files and consistency graphs.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <istream>
#include <limits>
#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace hairmvs {

constexpr uint64_t kInvalidPoint3DId = std::numeric_limits<uint64_t>::max();

// COLMAP's camera models by id (0-10: COLMAP 3.8; 11-17: later releases).
struct CameraModelInfo {
  int id;
  const char* name;
  int num_params;
  // The focal lengths are params[0, num_focal_params): f (1), fx and fy (2), or none (0, for
  // EQUIRECTANGULAR). The readers refuse a focal length that is not > 0.
  int num_focal_params;
  const char* params_info;  // parameter names in order, as COLMAP's params_info: "fx, fy, cx, cy"
};
const std::vector<CameraModelInfo>& CameraModels();
// Throws hairmvs::Error for an unknown id / name.
const CameraModelInfo& CameraModelById(int model_id);
const CameraModelInfo& CameraModelByName(const std::string& name);
// The name of parameter `index` (0-based) of the model, e.g. "fy"; "?" when out of range.
std::string CameraParamName(const CameraModelInfo& info, int index);

// Readers refuse a camera width or height outside [1, kMaxCameraSizePx] (the maps are sized in
// int, and no real camera is wider).
constexpr uint64_t kMaxCameraSizePx = 1000000;

struct Camera {
  uint32_t camera_id = 0;
  int model_id = 1;  // PINHOLE
  uint64_t width = 0;
  uint64_t height = 0;
  std::vector<double> params;

  std::string ModelName() const;
  // What the dense stage takes: PINHOLE or SIMPLE_PINHOLE, or a perspective model whose
  // distortion parameters are all 0 (SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV), which colmap
  // image_undistorter copies through as it is (its Camera::IsUndistorted), and so is in COLMAP
  // workspaces that colmap patch_match_stereo reads.
  bool IsPinhole() const;
  // Throws hairmvs::Error unless IsPinhole(), telling the user to run `colmap
  // image_undistorter`: the one message for a distorted camera. `where` (e.g. "Image a.png in
  // <workspace>/sparse") leads it when given.
  void RequirePinhole(const std::string& where = "") const;
  // K (from f or fx, fy, then cx, cy) for a camera that IsPinhole(). Throws hairmvs::Error for
  // any other, as
  // RequirePinhole() does (without a location: Workspace::CameraOf names the model folder).
  Eigen::Matrix3d CalibrationMatrix() const;
};

struct Point2D {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  // SfM pixel convention (centre of pixel 0 at 0.5)
  uint64_t point3D_id = kInvalidPoint3DId;
};

struct Image {
  uint32_t image_id = 0;
  uint32_t camera_id = 0;
  std::string name;
  // cam_from_world: X_cam = R * X_world + t. Quaternion is Hamilton, stored (w, x, y, z) in files.
  Eigen::Quaterniond cam_from_world_rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d cam_from_world_translation = Eigen::Vector3d::Zero();
  std::vector<Point2D> points2D;

  Eigen::Matrix3d R() const { return cam_from_world_rotation.toRotationMatrix(); }
  const Eigen::Vector3d& t() const { return cam_from_world_translation; }
  Eigen::Vector3d ProjectionCenter() const { return -(R().transpose() * t()); }
  // Unit viewing direction (camera +z) in world coordinates.
  Eigen::Vector3d ViewingDirection() const { return R().row(2).transpose(); }
};

struct TrackElement {
  uint32_t image_id = 0;
  uint32_t point2D_idx = 0;
};

struct Point3D {
  uint64_t point3D_id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  uint8_t rgb[3] = {0, 0, 0};
  double error = -1.0;
  std::vector<TrackElement> track;
};

struct Reconstruction {
  std::map<uint32_t, Camera> cameras;
  std::map<uint32_t, Image> images;
  std::map<uint64_t, Point3D> points3D;
  // Image ids in the order of the records of images.bin / images.txt as read (COLMAP 3.8's
  // image_idx). Models built in memory or written by us use ascending ids.
  std::vector<uint32_t> image_order;

  const Image& ImageByName(const std::string& name) const;  // throws hairmvs::Error
  const Image* FindImageByName(const std::string& name) const;
  // Fills image_order with ascending ids (what our writers write).
  void SortImageOrder();
};

enum class ModelFormat { kBinary, kText };

// Reads `dir`: binary when cameras.bin, images.bin and points3D.bin all exist, else text
// (COLMAP's rule). Accepts and ignores rigs.* / frames.* (COLMAP 3.12+). Throws hairmvs::Error
// naming the file (and the line, for text) and the problem (missing files, truncated, trailing
// bytes, unknown model id, wrong parameter count, malformed line, a camera size outside
// [1, kMaxCameraSizePx], a parameter that is nan or inf, a focal length that is not > 0, two
// images with the same name, a translation that is nan or inf).
// A model whose tracks and keypoints disagree still reads (source views and depth ranges pass
// over what does not resolve), with a warning that DescribeTrackInconsistencies words; so does
// a model with an implausible calibration, with DescribeImplausibleCameras's warning.
Reconstruction ReadReconstruction(const std::string& dir);

// COLMAP's own test of a calibration that is likely wrong (Camera::HasBogusParams with the
// mapper's defaults, min_focal_length_ratio 0.1 and max_focal_length_ratio 10): a focal length
// outside 0.1-10 times the larger image side, a principal point outside the image. COLMAP's
// dense code takes such a camera as it is, and so does hairmvs; a long lens can pass the
// limits rightly (the mapper's ratios can be changed), but a wrong calibration gives depth maps
// that are empty or wrong with no other sign; so the warning names each camera and what is
// wrong with it. Empty when every camera passes. `cameras_file` is where they were read from.
std::string DescribeImplausibleCameras(const Reconstruction& reconstruction,
                                       const std::string& cameras_file);

// What of the model's sparse points does not resolve, one sentence per kind (empty when
// everything does): track elements naming an image that is not in the model or a keypoint
// index beyond that image's keypoints, and keypoints naming a 3D point that is not there.
// `points_file` / `images_file` name where each kind was read from.
std::string DescribeTrackInconsistencies(const Reconstruction& reconstruction,
                                         const std::string& points_file,
                                         const std::string& images_file);

// Writes cameras, images and points3D sorted by id, exactly as COLMAP 3.8 reads them, as one
// unit (WriteFilesAtomically): if any file fails, the old model is left whole. Throws
// hairmvs::Error naming `dir` for a text model where all three .bin files are (readers would
// keep reading those).
void WriteReconstruction(const Reconstruction& reconstruction, const std::string& dir,
                         ModelFormat format);

// Stream versions, for tests that round-trip through memory. `source` names the stream in
// error messages.
void ReadCamerasBinary(std::istream& in, const std::string& source, Reconstruction* r);
void ReadImagesBinary(std::istream& in, const std::string& source, Reconstruction* r);
void ReadPoints3DBinary(std::istream& in, const std::string& source, Reconstruction* r);
void ReadCamerasText(std::istream& in, const std::string& source, Reconstruction* r);
void ReadImagesText(std::istream& in, const std::string& source, Reconstruction* r);
void ReadPoints3DText(std::istream& in, const std::string& source, Reconstruction* r);
void WriteCamerasBinary(const Reconstruction& r, std::ostream& out);
void WriteImagesBinary(const Reconstruction& r, std::ostream& out);
void WritePoints3DBinary(const Reconstruction& r, std::ostream& out);
void WriteCamerasText(const Reconstruction& r, std::ostream& out);
void WriteImagesText(const Reconstruction& r, std::ostream& out);
void WritePoints3DText(const Reconstruction& r, std::ostream& out);

}  // namespace hairmvs
