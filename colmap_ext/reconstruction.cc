#include "colmap_ext/reconstruction.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <mutex>
#include <set>
#include <sstream>

#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace hairmvs {

static_assert(sizeof(double) == 8, "IEEE-754 double expected");

const std::vector<CameraModelInfo>& CameraModels() {
  // colmap-formats.md section 4.2 (ids, parameter counts and names of COLMAP 3.8 through 4.1;
  // the focal lengths lead, as in COLMAP's focal_length_idxs).
  static const std::vector<CameraModelInfo> kModels = {
      {0, "SIMPLE_PINHOLE", 3, 1, "f, cx, cy"},
      {1, "PINHOLE", 4, 2, "fx, fy, cx, cy"},
      {2, "SIMPLE_RADIAL", 4, 1, "f, cx, cy, k"},
      {3, "RADIAL", 5, 1, "f, cx, cy, k1, k2"},
      {4, "OPENCV", 8, 2, "fx, fy, cx, cy, k1, k2, p1, p2"},
      {5, "OPENCV_FISHEYE", 8, 2, "fx, fy, cx, cy, k1, k2, k3, k4"},
      {6, "FULL_OPENCV", 12, 2, "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6"},
      {7, "FOV", 5, 2, "fx, fy, cx, cy, omega"},
      {8, "SIMPLE_RADIAL_FISHEYE", 4, 1, "f, cx, cy, k"},
      {9, "RADIAL_FISHEYE", 5, 1, "f, cx, cy, k1, k2"},
      {10, "THIN_PRISM_FISHEYE", 12, 2, "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1"},
      {11, "RAD_TAN_THIN_PRISM_FISHEYE", 16, 2,
       "fx, fy, cx, cy, k0, k1, k2, k3, k4, k5, p0, p1, s0, s1, s2, s3"},
      {12, "SIMPLE_DIVISION", 4, 1, "f, cx, cy, k"},
      {13, "DIVISION", 5, 2, "fx, fy, cx, cy, k"},
      {14, "SIMPLE_FISHEYE", 3, 1, "f, cx, cy"},
      {15, "FISHEYE", 4, 2, "fx, fy, cx, cy"},
      {16, "EUCM", 6, 2, "fx, fy, cx, cy, alpha, beta"},
      {17, "EQUIRECTANGULAR", 2, 0, "w, h"},
  };
  return kModels;
}

const CameraModelInfo& CameraModelById(int model_id) {
  for (const CameraModelInfo& info : CameraModels()) {
    if (info.id == model_id) return info;
  }
  HAIRMVS_THROW("Unknown camera model id " << model_id << " (known: 0-17)");
}

const CameraModelInfo& CameraModelByName(const std::string& name) {
  for (const CameraModelInfo& info : CameraModels()) {
    if (name == info.name) return info;
  }
  HAIRMVS_THROW("Unknown camera model name '" << name << "'");
}

std::string CameraParamName(const CameraModelInfo& info, int index) {
  std::istringstream names(info.params_info);
  std::string name;
  for (int k = 0; std::getline(names, name, ','); ++k) {
    if (k == index) return StripWhitespace(name);
  }
  return "?";
}

std::string Camera::ModelName() const { return CameraModelById(model_id).name; }

// SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV: a pinhole (f or fx, fy, then cx, cy) with lens
// distortion after it, which is a pinhole when all 0. Not the fisheye models, whose projection
// is not perspective even without distortion.
namespace {
bool IsDistortedPinholeModel(int model_id) {
  return model_id == 2 || model_id == 3 || model_id == 4 || model_id == 6;
}
}  // namespace

bool Camera::IsPinhole() const {
  if (model_id == 0 || model_id == 1) return true;
  if (!IsDistortedPinholeModel(model_id)) return false;
  const size_t first_distortion = CameraModelById(model_id).num_focal_params + 2;
  return params.size() == static_cast<size_t>(CameraModelById(model_id).num_params) &&
         std::all_of(params.begin() + first_distortion, params.end(),
                     [](double p) { return p == 0.0; });
}

void Camera::RequirePinhole(const std::string& where) const {
  THROW_IF(!IsPinhole(), (where.empty() ? "Camera " : where + ": camera ")
                             << camera_id << " has model " << ModelName()
                             << (IsDistortedPinholeModel(model_id) ? " with distortion" : "")
                             << "; the dense stage needs undistorted PINHOLE or SIMPLE_PINHOLE "
                                "cameras (or SIMPLE_RADIAL, RADIAL, OPENCV or FULL_OPENCV with "
                                "every distortion parameter 0): run `colmap image_undistorter "
                                "--output_type COLMAP` first");
}

Eigen::Matrix3d Camera::CalibrationMatrix() const {
  RequirePinhole();
  THROW_IF(params.size() != static_cast<size_t>(CameraModelById(model_id).num_params),
           "Camera " << camera_id << " has " << params.size() << " parameters for "
                     << ModelName());
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  const int num_focal = CameraModelById(model_id).num_focal_params;  // 1 or 2 here
  K(0, 0) = params[0];
  K(1, 1) = params[num_focal - 1];
  K(0, 2) = params[num_focal];
  K(1, 2) = params[num_focal + 1];
  return K;
}

const Image* Reconstruction::FindImageByName(const std::string& name) const {
  for (const auto& [id, image] : images) {
    if (image.name == name) return &image;
  }
  return nullptr;
}

const Image& Reconstruction::ImageByName(const std::string& name) const {
  const Image* image = FindImageByName(name);
  THROW_IF(image == nullptr, "Image with name `" << name << "` does not exist in the model");
  return *image;
}

void Reconstruction::SortImageOrder() {
  image_order.clear();
  for (const auto& [id, image] : images) image_order.push_back(id);
}

// ---------------------------------------------------------------------------------------------
// Binary helpers.

namespace {

template <typename T>
T ReadBinary(std::istream& in, const std::string& source, const char* what) {
  T value;
  in.read(reinterpret_cast<char*>(&value), sizeof(T));
  THROW_IF(in.gcount() != static_cast<std::streamsize>(sizeof(T)),
           source << ": truncated file while reading " << what);
  return value;  // little-endian host assumed (x86-64, aarch64), as COLMAP does
}

template <typename T>
void WriteBinary(std::ostream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

void RequireEnd(std::istream& in, const std::string& source) {
  if (in.peek() == std::char_traits<char>::eof()) return;
  const std::streampos pos = in.tellg();
  in.clear();
  in.seekg(0, std::ios::end);
  const std::streampos end = in.tellg();
  HAIRMVS_THROW(source << ": " << (end - pos)
                       << " unexpected bytes after the last record (oversized file, or a "
                          "count that does not match the records)");
}

// Bounded reserve: a corrupt count must not allocate terabytes before the truncation shows.
template <typename V>
void ReserveBounded(V* v, uint64_t n) {
  v->reserve(static_cast<size_t>(std::min<uint64_t>(n, 1u << 16)));
}

// ---------------------------------------------------------------------------------------------
// Text helpers: COLMAP 3.8 splits on single spaces after trimming the line (section 4.5).

struct TextLine {
  std::vector<std::string> tokens;
  int line_number = 0;
};

// Splits a trimmed line on single spaces. A doubled space (empty token) or a tab is rejected:
// COLMAP 3.8 aborts on such a file, so we name the problem instead.
std::vector<std::string> SplitSingleSpaces(const std::string& line, const std::string& where) {
  std::vector<std::string> tokens;
  if (line.empty()) return tokens;
  THROW_IF(line.find('\t') != std::string::npos,
           where << ": tab character; COLMAP 3.8 text files separate tokens by single spaces");
  size_t start = 0;
  while (true) {
    const size_t pos = line.find(' ', start);
    std::string token = line.substr(start, pos == std::string::npos ? std::string::npos
                                                                     : pos - start);
    THROW_IF(token.empty(), where << ": doubled space; COLMAP 3.8 text files separate tokens "
                                     "by exactly one space (3.8 aborts on this)");
    tokens.push_back(std::move(token));
    if (pos == std::string::npos) break;
    start = pos + 1;
  }
  return tokens;
}

std::string TrimLine(std::string line) { return StripWhitespace(line); }

std::string Where(const std::string& source, int line_number) {
  std::ostringstream ss;
  ss << source << ":" << line_number;
  return ss.str();
}

template <typename T>
T ParseInteger(const std::string& token, const std::string& where, const char* what) {
  T value{};
  const char* begin = token.data();
  const char* end = token.data() + token.size();
  const auto result = std::from_chars(begin, end, value);
  THROW_IF(result.ec != std::errc() || result.ptr != end,
           where << ": cannot parse " << what << " from '" << token << "'");
  return value;
}

// strtod reports ERANGE for an underflow too (1e-310, which COLMAP reads and writes as a
// denormal); only an overflow, which comes back as +-HUGE_VAL, is not a number we can use.
double ParseDouble(const std::string& token, const std::string& where, const char* what) {
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(token.c_str(), &end);
  const bool overflow = errno == ERANGE && std::abs(value) == HUGE_VAL;
  THROW_IF(end != token.c_str() + token.size() || token.empty() || overflow,
           where << ": cannot parse " << what << " from '" << token << "'");
  return value;
}

// Point3D ids in text: -1 means none.
uint64_t ParsePoint3DId(const std::string& token, const std::string& where) {
  if (token == "-1") return kInvalidPoint3DId;
  return ParseInteger<uint64_t>(token, where, "POINT3D_ID");
}

Eigen::Quaterniond NormalizedQuaternion(double qw, double qx, double qy, double qz,
                                        const std::string& where) {
  Eigen::Quaterniond q(qw, qx, qy, qz);
  const double norm = q.norm();
  THROW_IF(!(norm > 1e-12) || !std::isfinite(norm),
           where << ": invalid rotation quaternion (norm " << norm << ")");
  // COLMAP 3.8 normalises quaternions when reading (section 4.3).
  q.coeffs() /= norm;
  return q;
}

void SetCameraParams(Camera* camera, std::vector<double> params, const std::string& where) {
  const CameraModelInfo& info = CameraModelById(camera->model_id);
  THROW_IF(params.size() != static_cast<size_t>(info.num_params),
           where << ": camera " << camera->camera_id << " of model " << info.name << " has "
                 << params.size() << " parameters, expected " << info.num_params);
  camera->params = std::move(params);
}

// What the dense stage cannot use and would otherwise only trip over later (a CHECK on a map
// of size 0, a negative int size, empty depth maps written over good ones): a width or height
// outside [1, kMaxCameraSizePx], a parameter that is nan or inf, a focal length that is not > 0.
// `where` is the file (binary) or file:line (text).
void ValidateCamera(const Camera& camera, const std::string& where) {
  const CameraModelInfo& info = CameraModelById(camera.model_id);
  const std::pair<const char*, uint64_t> sizes[] = {{"width", camera.width},
                                                    {"height", camera.height}};
  for (const auto& [what, size] : sizes) {
    THROW_IF(size < 1 || size > kMaxCameraSizePx,
             where << ": camera " << camera.camera_id << ": " << what << " " << size
                   << " is outside 1.." << kMaxCameraSizePx << " px");
  }
  for (size_t k = 0; k < camera.params.size(); ++k) {
    const double value = camera.params[k];
    const int index = static_cast<int>(k);
    THROW_IF(!std::isfinite(value),
             where << ": camera " << camera.camera_id << ": parameter " << index + 1 << " ("
                   << CameraParamName(info, index) << " of " << info.name << ") is " << value);
    THROW_IF(index < info.num_focal_params && !(value > 0),
             where << ": camera " << camera.camera_id << ": focal length "
                   << CameraParamName(info, index) << " (parameter " << index + 1 << " of "
                   << info.name << ") is " << value << "; it must be > 0");
  }
}

// A pose the dense stage can use: a translation of finite numbers (the quaternion is checked
// by NormalizedQuaternion). `where` names the file and the image (binary) or the line (text).
void ValidateTranslation(const Eigen::Vector3d& translation, const std::string& where) {
  THROW_IF(!translation.allFinite(), where << ": translation (" << translation.x() << ", "
                                           << translation.y() << ", " << translation.z()
                                           << ") is not finite");
}

// Image names are unique in a model (COLMAP requires it; maps are named after images).
// `names` maps the names read so far to their image ids.
void RequireUniqueName(const Image& image, const std::string& where,
                       std::map<std::string, uint32_t>* names) {
  const auto [it, inserted] = names->emplace(image.name, image.image_id);
  THROW_IF(!inserted, where << ": images " << it->second << " and " << image.image_id
                            << " both have the name " << image.name
                            << " (image names must be unique)");
}

std::map<std::string, uint32_t> ImageNames(const Reconstruction& r) {
  std::map<std::string, uint32_t> names;
  for (const auto& [id, image] : r.images) names.emplace(image.name, id);
  return names;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Binary readers.

void ReadCamerasBinary(std::istream& in, const std::string& source, Reconstruction* r) {
  const uint64_t num_cameras = ReadBinary<uint64_t>(in, source, "num_cameras");
  for (uint64_t i = 0; i < num_cameras; ++i) {
    Camera camera;
    camera.camera_id = ReadBinary<uint32_t>(in, source, "camera_id");
    const int32_t model_id = ReadBinary<int32_t>(in, source, "model_id");
    const CameraModelInfo* info = nullptr;
    try {
      info = &CameraModelById(model_id);
    } catch (const Error& e) {
      HAIRMVS_THROW(source << ": camera " << camera.camera_id << ": " << e.what());
    }
    camera.model_id = model_id;
    camera.width = ReadBinary<uint64_t>(in, source, "camera width");
    camera.height = ReadBinary<uint64_t>(in, source, "camera height");
    camera.params.resize(info->num_params);
    for (double& p : camera.params) p = ReadBinary<double>(in, source, "camera parameters");
    ValidateCamera(camera, source);
    THROW_IF(r->cameras.count(camera.camera_id),
             source << ": duplicate camera_id " << camera.camera_id);
    r->cameras[camera.camera_id] = std::move(camera);
  }
  RequireEnd(in, source);
}

void ReadImagesBinary(std::istream& in, const std::string& source, Reconstruction* r) {
  const uint64_t num_images = ReadBinary<uint64_t>(in, source, "num_reg_images");
  r->image_order.clear();
  std::map<std::string, uint32_t> names = ImageNames(*r);
  ReserveBounded(&r->image_order, num_images);
  for (uint64_t i = 0; i < num_images; ++i) {
    Image image;
    image.image_id = ReadBinary<uint32_t>(in, source, "image_id");
    double q[4];
    for (double& v : q) v = ReadBinary<double>(in, source, "image rotation");
    std::ostringstream where;
    where << source << ": image " << image.image_id;
    image.cam_from_world_rotation = NormalizedQuaternion(q[0], q[1], q[2], q[3], where.str());
    for (int k = 0; k < 3; ++k) {
      image.cam_from_world_translation[k] = ReadBinary<double>(in, source, "image translation");
    }
    ValidateTranslation(image.cam_from_world_translation, where.str());
    image.camera_id = ReadBinary<uint32_t>(in, source, "image camera_id");
    // NUL-terminated name.
    std::string name;
    while (true) {
      const char c = ReadBinary<char>(in, source, "image name (no terminating NUL)");
      if (c == '\0') break;
      name.push_back(c);
      THROW_IF(name.size() > 65536, source << ": image name longer than 64 KiB (corrupt file)");
    }
    THROW_IF(name.empty(), where.str() << ": empty image name");
    image.name = std::move(name);
    const uint64_t num_points2D = ReadBinary<uint64_t>(in, source, "num_points2D");
    ReserveBounded(&image.points2D, num_points2D);
    for (uint64_t k = 0; k < num_points2D; ++k) {
      Point2D p;
      p.xy.x() = ReadBinary<double>(in, source, "point2D x");
      p.xy.y() = ReadBinary<double>(in, source, "point2D y");
      p.point3D_id = ReadBinary<uint64_t>(in, source, "point2D point3D_id");
      image.points2D.push_back(p);
    }
    THROW_IF(r->images.count(image.image_id),
             source << ": duplicate image_id " << image.image_id);
    RequireUniqueName(image, source, &names);
    r->image_order.push_back(image.image_id);
    r->images[image.image_id] = std::move(image);
  }
  RequireEnd(in, source);
}

void ReadPoints3DBinary(std::istream& in, const std::string& source, Reconstruction* r) {
  const uint64_t num_points = ReadBinary<uint64_t>(in, source, "num_points3D");
  for (uint64_t i = 0; i < num_points; ++i) {
    Point3D point;
    point.point3D_id = ReadBinary<uint64_t>(in, source, "point3D_id");
    for (int k = 0; k < 3; ++k) point.xyz[k] = ReadBinary<double>(in, source, "point3D xyz");
    for (int k = 0; k < 3; ++k) point.rgb[k] = ReadBinary<uint8_t>(in, source, "point3D rgb");
    point.error = ReadBinary<double>(in, source, "point3D error");
    const uint64_t track_length = ReadBinary<uint64_t>(in, source, "track_length");
    ReserveBounded(&point.track, track_length);
    for (uint64_t k = 0; k < track_length; ++k) {
      TrackElement el;
      el.image_id = ReadBinary<uint32_t>(in, source, "track image_id");
      el.point2D_idx = ReadBinary<uint32_t>(in, source, "track point2D_idx");
      point.track.push_back(el);
    }
    THROW_IF(r->points3D.count(point.point3D_id),
             source << ": duplicate point3D_id " << point.point3D_id);
    r->points3D[point.point3D_id] = std::move(point);
  }
  RequireEnd(in, source);
}

// ---------------------------------------------------------------------------------------------
// Text readers.

void ReadCamerasText(std::istream& in, const std::string& source, Reconstruction* r) {
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    line = TrimLine(line);
    if (line.empty() || line[0] == '#') continue;
    const std::string where = Where(source, line_number);
    const std::vector<std::string> tokens = SplitSingleSpaces(line, where);
    THROW_IF(tokens.size() < 4,
             where << ": expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[], found " << tokens.size()
                   << " tokens");
    Camera camera;
    camera.camera_id = ParseInteger<uint32_t>(tokens[0], where, "CAMERA_ID");
    try {
      camera.model_id = CameraModelByName(tokens[1]).id;
    } catch (const Error& e) {
      HAIRMVS_THROW(where << ": " << e.what());
    }
    camera.width = ParseInteger<uint64_t>(tokens[2], where, "WIDTH");
    camera.height = ParseInteger<uint64_t>(tokens[3], where, "HEIGHT");
    std::vector<double> params;
    for (size_t k = 4; k < tokens.size(); ++k) {
      params.push_back(ParseDouble(tokens[k], where, "camera parameter"));
    }
    SetCameraParams(&camera, std::move(params), where);
    ValidateCamera(camera, where);
    THROW_IF(r->cameras.count(camera.camera_id),
             where << ": duplicate camera_id " << camera.camera_id);
    r->cameras[camera.camera_id] = std::move(camera);
  }
}

void ReadImagesText(std::istream& in, const std::string& source, Reconstruction* r) {
  std::string line;
  int line_number = 0;
  r->image_order.clear();
  std::map<std::string, uint32_t> names = ImageNames(*r);
  while (std::getline(in, line)) {
    ++line_number;
    line = TrimLine(line);
    // Only the first line of a pair may be a comment or empty (section 4.3).
    if (line.empty() || line[0] == '#') continue;
    const std::string where = Where(source, line_number);
    const std::vector<std::string> tokens = SplitSingleSpaces(line, where);
    THROW_IF(tokens.size() != 10,
             where << ": expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME (10 tokens), found "
                   << tokens.size() << " (image names must not contain spaces)");
    Image image;
    image.image_id = ParseInteger<uint32_t>(tokens[0], where, "IMAGE_ID");
    double q[4];
    for (int k = 0; k < 4; ++k) q[k] = ParseDouble(tokens[1 + k], where, "quaternion");
    image.cam_from_world_rotation = NormalizedQuaternion(q[0], q[1], q[2], q[3], where);
    for (int k = 0; k < 3; ++k) {
      image.cam_from_world_translation[k] = ParseDouble(tokens[5 + k], where, "translation");
    }
    ValidateTranslation(image.cam_from_world_translation, where);
    image.camera_id = ParseInteger<uint32_t>(tokens[8], where, "CAMERA_ID");
    image.name = tokens[9];
    // The second line (POINTS2D) is required, even when empty.
    THROW_IF(!std::getline(in, line),
             where << ": image " << image.image_id
                   << " has no second line (POINTS2D[] as X Y POINT3D_ID; write an empty line "
                      "when there are none)");
    ++line_number;
    line = TrimLine(line);
    const std::string where2 = Where(source, line_number);
    THROW_IF(!line.empty() && line[0] == '#',
             where2 << ": expected the POINTS2D line of image " << image.image_id
                    << ", found a comment (two lines per image)");
    const std::vector<std::string> p = SplitSingleSpaces(line, where2);
    THROW_IF(p.size() % 3 != 0,
             where2 << ": POINTS2D line of image " << image.image_id << " has " << p.size()
                    << " tokens, not a multiple of 3 (X Y POINT3D_ID)");
    for (size_t k = 0; k < p.size(); k += 3) {
      Point2D point;
      point.xy.x() = ParseDouble(p[k], where2, "point2D X");
      point.xy.y() = ParseDouble(p[k + 1], where2, "point2D Y");
      point.point3D_id = ParsePoint3DId(p[k + 2], where2);
      image.points2D.push_back(point);
    }
    THROW_IF(r->images.count(image.image_id),
             where << ": duplicate image_id " << image.image_id);
    RequireUniqueName(image, where, &names);
    r->image_order.push_back(image.image_id);
    r->images[image.image_id] = std::move(image);
  }
}

void ReadPoints3DText(std::istream& in, const std::string& source, Reconstruction* r) {
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    line = TrimLine(line);
    if (line.empty() || line[0] == '#') continue;
    const std::string where = Where(source, line_number);
    const std::vector<std::string> tokens = SplitSingleSpaces(line, where);
    THROW_IF(tokens.size() < 8 || (tokens.size() - 8) % 2 != 0,
             where << ": expected POINT3D_ID X Y Z R G B ERROR (IMAGE_ID POINT2D_IDX)*, found "
                   << tokens.size() << " tokens");
    Point3D point;
    point.point3D_id = ParseInteger<uint64_t>(tokens[0], where, "POINT3D_ID");
    for (int k = 0; k < 3; ++k) point.xyz[k] = ParseDouble(tokens[1 + k], where, "X/Y/Z");
    for (int k = 0; k < 3; ++k) {
      const int value = ParseInteger<int>(tokens[4 + k], where, "R/G/B");
      THROW_IF(value < 0 || value > 255, where << ": colour " << value << " outside 0-255");
      point.rgb[k] = static_cast<uint8_t>(value);
    }
    point.error = ParseDouble(tokens[7], where, "ERROR");
    for (size_t k = 8; k < tokens.size(); k += 2) {
      TrackElement el;
      el.image_id = ParseInteger<uint32_t>(tokens[k], where, "track IMAGE_ID");
      el.point2D_idx = ParseInteger<uint32_t>(tokens[k + 1], where, "track POINT2D_IDX");
      point.track.push_back(el);
    }
    THROW_IF(r->points3D.count(point.point3D_id),
             where << ": duplicate point3D_id " << point.point3D_id);
    r->points3D[point.point3D_id] = std::move(point);
  }
}

// ---------------------------------------------------------------------------------------------
// Writers: every record sorted by id.

namespace {

// Sorted by image_id, as the header promises: the file order is COLMAP 3.8's image_idx, so
// whoever writes .vis indices must number images by ascending id (SortImageOrder()).
std::vector<uint32_t> ImageWriteOrder(const Reconstruction& r) {
  std::vector<uint32_t> order;
  for (const auto& [id, image] : r.images) order.push_back(id);
  return order;
}

void CheckCamera(const Camera& camera) {
  const CameraModelInfo& info = CameraModelById(camera.model_id);
  CHECK_EQ(camera.params.size(), static_cast<size_t>(info.num_params))
      << "camera " << camera.camera_id << " of model " << info.name;
}

void CheckWritableName(const std::string& name) {
  THROW_IF(name.empty() || name.find_first_of(" \t\r\n") != std::string::npos ||
               name.find('\0') != std::string::npos,
           "Image name '" << name << "' cannot be written: COLMAP names must be non-empty and "
                             "contain no whitespace");
}

Eigen::Quaterniond UnitQuaternion(const Eigen::Quaterniond& q) {
  return Eigen::Quaterniond(q.coeffs() / q.norm());
}

}  // namespace

void WriteCamerasBinary(const Reconstruction& r, std::ostream& out) {
  WriteBinary<uint64_t>(out, r.cameras.size());
  for (const auto& [id, camera] : r.cameras) {
    CheckCamera(camera);
    WriteBinary<uint32_t>(out, camera.camera_id);
    WriteBinary<int32_t>(out, camera.model_id);
    WriteBinary<uint64_t>(out, camera.width);
    WriteBinary<uint64_t>(out, camera.height);
    for (double p : camera.params) WriteBinary<double>(out, p);
  }
}

void WriteImagesBinary(const Reconstruction& r, std::ostream& out) {
  WriteBinary<uint64_t>(out, r.images.size());
  for (uint32_t id : ImageWriteOrder(r)) {
    const Image& image = r.images.at(id);
    CheckWritableName(image.name);
    WriteBinary<uint32_t>(out, image.image_id);
    const Eigen::Quaterniond q = UnitQuaternion(image.cam_from_world_rotation);
    WriteBinary<double>(out, q.w());
    WriteBinary<double>(out, q.x());
    WriteBinary<double>(out, q.y());
    WriteBinary<double>(out, q.z());
    for (int k = 0; k < 3; ++k) WriteBinary<double>(out, image.cam_from_world_translation[k]);
    WriteBinary<uint32_t>(out, image.camera_id);
    out.write(image.name.c_str(), static_cast<std::streamsize>(image.name.size() + 1));
    WriteBinary<uint64_t>(out, image.points2D.size());
    for (const Point2D& p : image.points2D) {
      WriteBinary<double>(out, p.xy.x());
      WriteBinary<double>(out, p.xy.y());
      WriteBinary<uint64_t>(out, p.point3D_id);
    }
  }
}

void WritePoints3DBinary(const Reconstruction& r, std::ostream& out) {
  WriteBinary<uint64_t>(out, r.points3D.size());
  for (const auto& [id, point] : r.points3D) {
    WriteBinary<uint64_t>(out, point.point3D_id);
    for (int k = 0; k < 3; ++k) WriteBinary<double>(out, point.xyz[k]);
    for (int k = 0; k < 3; ++k) WriteBinary<uint8_t>(out, point.rgb[k]);
    WriteBinary<double>(out, point.error);
    WriteBinary<uint64_t>(out, point.track.size());
    for (const TrackElement& el : point.track) {
      WriteBinary<uint32_t>(out, el.image_id);
      WriteBinary<uint32_t>(out, el.point2D_idx);
    }
  }
}

// Text: 17 significant digits so that doubles round-trip exactly; single spaces only.
void WriteCamerasText(const Reconstruction& r, std::ostream& out) {
  out << std::setprecision(17);
  out << "# Camera list with one line of data per camera:\n"
      << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      << "# Number of cameras: " << r.cameras.size() << "\n";
  for (const auto& [id, camera] : r.cameras) {
    CheckCamera(camera);
    out << camera.camera_id << " " << camera.ModelName() << " " << camera.width << " "
        << camera.height;
    for (double p : camera.params) out << " " << p;
    out << "\n";
  }
}

void WriteImagesText(const Reconstruction& r, std::ostream& out) {
  out << std::setprecision(17);
  size_t num_observations = 0;
  for (const auto& [id, image] : r.images) num_observations += image.points2D.size();
  out << "# Image list with two lines of data per image:\n"
      << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      << "# Number of images: " << r.images.size()
      << ", mean observations per image: "
      << (r.images.empty() ? 0.0 : static_cast<double>(num_observations) / r.images.size())
      << "\n";
  for (uint32_t id : ImageWriteOrder(r)) {
    const Image& image = r.images.at(id);
    CheckWritableName(image.name);
    const Eigen::Quaterniond q = UnitQuaternion(image.cam_from_world_rotation);
    const Eigen::Vector3d& t = image.cam_from_world_translation;
    out << image.image_id << " " << q.w() << " " << q.x() << " " << q.y() << " " << q.z() << " "
        << t.x() << " " << t.y() << " " << t.z() << " " << image.camera_id << " " << image.name
        << "\n";
    bool first = true;
    for (const Point2D& p : image.points2D) {
      if (!first) out << " ";
      first = false;
      out << p.xy.x() << " " << p.xy.y() << " ";
      if (p.point3D_id == kInvalidPoint3DId) {
        out << -1;
      } else {
        out << p.point3D_id;
      }
    }
    out << "\n";
  }
}

void WritePoints3DText(const Reconstruction& r, std::ostream& out) {
  out << std::setprecision(17);
  size_t track_sum = 0;
  for (const auto& [id, point] : r.points3D) track_sum += point.track.size();
  out << "# 3D point list with one line of data per point:\n"
      << "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      << "# Number of points: " << r.points3D.size() << ", mean track length: "
      << (r.points3D.empty() ? 0.0 : static_cast<double>(track_sum) / r.points3D.size())
      << "\n";
  for (const auto& [id, point] : r.points3D) {
    out << point.point3D_id << " " << point.xyz.x() << " " << point.xyz.y() << " "
        << point.xyz.z() << " " << static_cast<int>(point.rgb[0]) << " "
        << static_cast<int>(point.rgb[1]) << " " << static_cast<int>(point.rgb[2]) << " "
        << point.error;
    for (const TrackElement& el : point.track) {
      out << " " << el.image_id << " " << el.point2D_idx;
    }
    out << "\n";
  }
}

// ---------------------------------------------------------------------------------------------
// Folders.

namespace {

void ReadFile(const std::string& path,
              void (*reader)(std::istream&, const std::string&, Reconstruction*),
              Reconstruction* r, bool binary) {
  std::ifstream in(path, binary ? std::ios::binary : std::ios::in);
  THROW_IF(!in, "Cannot open " << path);
  reader(in, path, r);
}

// The files of cameras, images, points3D with extension `ext` that exist in `dir` (`present`)
// or that do not (!`present`), in that order.
std::vector<std::string> ModelFilesPresent(const std::string& dir, const char* ext,
                                           bool present) {
  std::vector<std::string> names;
  for (const char* name : {"cameras", "images", "points3D"}) {
    const std::string file = std::string(name) + ext;
    if (ExistsFile(JoinPaths(dir, file)) == present) names.push_back(file);
  }
  return names;
}

// Whether `dir` holds all three of cameras, images and points3D with the extension `ext`.
bool HasModelFiles(const std::string& dir, const char* ext) {
  return ModelFilesPresent(dir, ext, false).empty();
}

// "a", "a and b", "a, b and c".
std::string JoinWithAnd(const std::vector<std::string>& items) {
  if (items.size() < 2) return JoinStrings(items, "");
  const std::vector<std::string> all_but_last(items.begin(), items.end() - 1);
  return JoinStrings(all_but_last, ", ") + " and " + items.back();
}

}  // namespace

Reconstruction ReadReconstruction(const std::string& dir) {
  THROW_IF(!ExistsDir(dir), "Missing sparse model folder: " << dir);
  Reconstruction r;
  // COLMAP's rule: binary if all three .bin files exist, else text. rigs.* / frames.*
  // (COLMAP 3.12+) are ignored: images.* still holds every pose.
  const bool binary = HasModelFiles(dir, ".bin");
  if (binary) {
    ReadFile(JoinPaths(dir, "cameras.bin"), ReadCamerasBinary, &r, true);
    ReadFile(JoinPaths(dir, "images.bin"), ReadImagesBinary, &r, true);
    ReadFile(JoinPaths(dir, "points3D.bin"), ReadPoints3DBinary, &r, true);
  } else if (HasModelFiles(dir, ".txt")) {
    ReadFile(JoinPaths(dir, "cameras.txt"), ReadCamerasText, &r, false);
    ReadFile(JoinPaths(dir, "images.txt"), ReadImagesText, &r, false);
    ReadFile(JoinPaths(dir, "points3D.txt"), ReadPoints3DText, &r, false);
  } else {
    std::ostringstream hint;
    if (ExistsDir(JoinPaths(dir, "0"))) {
      hint << " (found a sub-folder 0/: the model must sit directly in " << dir << ")";
    }
    // Name what is missing of the format more of whose files are there (binary on a tie, as
    // COLMAP prefers it); the old message only when there is none of the six files.
    const std::vector<std::string> bin = ModelFilesPresent(dir, ".bin", true);
    const std::vector<std::string> txt = ModelFilesPresent(dir, ".txt", true);
    const bool use_binary = bin.size() >= txt.size();
    const std::vector<std::string>& present = use_binary ? bin : txt;
    THROW_IF(present.empty(),
             "cameras, images, points3D files do not exist at "
                 << dir
                 << ": need all three of cameras.bin, images.bin, points3D.bin or of "
                    "cameras.txt, images.txt, points3D.txt"
                 << hint.str());
    const std::vector<std::string> missing =
        ModelFilesPresent(dir, use_binary ? ".bin" : ".txt", false);
    HAIRMVS_THROW(dir << ": missing " << JoinWithAnd(missing) << " ("
                      << JoinWithAnd(present) << (present.size() == 1 ? " is" : " are")
                      << " there; a model needs all three of cameras, images and points3D in one "
                         "format, .bin or .txt)"
                      << hint.str());
  }
  const std::string extension = binary ? ".bin" : ".txt";
  const std::string images_file = JoinPaths(dir, "images" + extension);
  for (const auto& [id, image] : r.images) {
    THROW_IF(!r.cameras.count(image.camera_id),
             images_file << ": image " << id << " (" << image.name << ") refers to camera "
                         << image.camera_id << ", which is not in the cameras file");
  }
  // A command reads one model several times (a pipeline up to seven): what is wrong with it
  // is said once per process and folder.
  static std::mutex mutex;
  static std::set<std::string> warned_about;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (!warned_about.insert(dir).second) return r;
  }
  const std::string implausible =
      DescribeImplausibleCameras(r, JoinPaths(dir, "cameras" + extension));
  if (!implausible.empty()) LOG(WARNING) << implausible;
  const std::string inconsistencies =
      DescribeTrackInconsistencies(r, JoinPaths(dir, "points3D" + extension), images_file);
  if (!inconsistencies.empty()) {
    LOG(WARNING) << inconsistencies
                 << " Source views and depth ranges pass over them; a model that COLMAP's "
                    "mapper or point_triangulator wrote has none.";
  }
  return r;
}

std::string DescribeImplausibleCameras(const Reconstruction& r, const std::string& cameras_file) {
  std::vector<std::string> implausible;
  for (const auto& [id, camera] : r.cameras) {
    const CameraModelInfo& info = CameraModelById(camera.model_id);
    if (info.num_focal_params == 0) continue;  // no focal length or principal point
    std::vector<std::string> problems;
    const double max_size = static_cast<double>(std::max(camera.width, camera.height));
    for (int k = 0; k < info.num_focal_params; ++k) {
      const double ratio = camera.params[k] / max_size;
      if (ratio < 0.1 || ratio > 10) {
        std::ostringstream problem;
        problem << CameraParamName(info, k) << " " << camera.params[k] << " is " << ratio
                << " times the larger side";
        problems.push_back(problem.str());
      }
    }
    const double cx = camera.params[info.num_focal_params];
    const double cy = camera.params[info.num_focal_params + 1];
    if (cx < 0 || cx > static_cast<double>(camera.width) || cy < 0 ||
        cy > static_cast<double>(camera.height)) {
      std::ostringstream problem;
      problem << "the principal point (" << cx << ", " << cy << ") lies outside the image";
      problems.push_back(problem.str());
    }
    if (problems.empty()) continue;
    std::ostringstream camera_text;
    camera_text << "camera " << id << " (" << info.name << ", " << camera.width << " x "
                << camera.height << " px): " << JoinStrings(problems, ", ");
    implausible.push_back(camera_text.str());
  }
  if (implausible.empty()) return "";
  return cameras_file + ": " + JoinStrings(implausible, "; ") +
         ". COLMAP's mapper discards such calibrations unless its "
         "--Mapper.min/max_focal_length_ratio were changed (focal length 0.1-10 times the larger "
         "side, principal point inside the image): check the calibration; depth maps from a "
         "wrong one come out empty or wrong.";
}

std::string DescribeTrackInconsistencies(const Reconstruction& reconstruction,
                                         const std::string& points_file,
                                         const std::string& images_file) {
  // How many of a kind, and the first, so that it can be looked up in the file.
  struct Count {
    size_t n = 0;
    std::string first;
  };
  Count unknown_image, bad_keypoint, unknown_point;
  size_t num_elements = 0, num_keypoints = 0;
  for (const auto& [point_id, point] : reconstruction.points3D) {
    for (const TrackElement& el : point.track) {
      ++num_elements;
      const auto image = reconstruction.images.find(el.image_id);
      if (image == reconstruction.images.end()) {
        if (unknown_image.n++ == 0) {
          unknown_image.first = "point " + std::to_string(point_id) + " -> image " +
                                std::to_string(el.image_id);
        }
      } else if (el.point2D_idx >= image->second.points2D.size() && bad_keypoint.n++ == 0) {
        bad_keypoint.first = "point " + std::to_string(point_id) + " -> keypoint " +
                             std::to_string(el.point2D_idx) + " of image " +
                             std::to_string(el.image_id) + " (" + image->second.name +
                             "), which has " + std::to_string(image->second.points2D.size());
      }
    }
  }
  for (const auto& [image_id, image] : reconstruction.images) {
    for (const Point2D& p : image.points2D) {
      if (p.point3D_id == kInvalidPoint3DId) continue;
      ++num_keypoints;
      if (!reconstruction.points3D.count(p.point3D_id) && unknown_point.n++ == 0) {
        unknown_point.first = "image " + std::to_string(image_id) + " (" + image.name +
                              ") -> point " + std::to_string(p.point3D_id);
      }
    }
  }
  std::ostringstream out;
  auto sentence = [&out](const std::string& file, const Count& count, size_t total,
                         const char* what) {
    if (count.n == 0) return;
    if (out.tellp() > 0) out << " ";
    out << file << ": " << count.n << " of " << total << " " << what << " (first: "
        << count.first << ").";
  };
  sentence(points_file, unknown_image, num_elements,
           "track elements name an image that is not in the model");
  sentence(points_file, bad_keypoint, num_elements,
           "track elements name a keypoint beyond their image's keypoints");
  sentence(images_file, unknown_point, num_keypoints,
           "triangulated keypoints name a 3D point that is not in the model");
  return out.str();
}

void WriteReconstruction(const Reconstruction& reconstruction, const std::string& dir,
                         ModelFormat format) {
  const bool binary = format == ModelFormat::kBinary;
  // Readers take the binary model whenever all three .bin files exist (COLMAP's rule): a text
  // model written beside them would be silently ignored, and deleting them is not ours to do.
  THROW_IF(!binary && HasModelFiles(dir, ".bin"),
           "Cannot write a text model to " << dir << ": it holds cameras.bin, images.bin and "
                                              "points3D.bin, which COLMAP and hairmvs read "
                                              "instead of text; remove them or write a binary "
                                              "model");
  using Writer = void (*)(const Reconstruction&, std::ostream&);
  auto file = [&](const char* name, Writer write_binary, Writer write_text) {
    const Writer write = binary ? write_binary : write_text;
    return FileToWrite{JoinPaths(dir, std::string(name) + (binary ? ".bin" : ".txt")),
                       [&reconstruction, write](std::ostream& out) { write(reconstruction, out); },
                       binary};
  };
  // One unit: a failure in any file (an image name COLMAP cannot read, a full disk) leaves the
  // old model whole rather than new cameras beside old images.
  WriteFilesAtomically({file("cameras", WriteCamerasBinary, WriteCamerasText),
                        file("images", WriteImagesBinary, WriteImagesText),
                        file("points3D", WritePoints3DBinary, WritePoints3DText)});
}

}  // namespace hairmvs
