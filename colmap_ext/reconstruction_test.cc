#include "colmap_ext/reconstruction.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <sstream>

#include "colmap_ext/test_util.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace hairmvs {
namespace {

using testing_util::ExpectModelsEqual;
using testing_util::MakePlaneModel;
using testing_util::MakeTestDir;

// Runs `f`, expects a hairmvs::Error whose message contains every one of `parts`.
template <typename F>
void ExpectErrorMentions(F&& f, const std::vector<std::string>& parts) {
  try {
    f();
    ADD_FAILURE() << "expected hairmvs::Error mentioning " << parts[0];
  } catch (const Error& e) {
    const std::string what = e.what();
    for (const std::string& part : parts) {
      EXPECT_NE(what.find(part), std::string::npos) << "'" << part << "' not in: " << what;
    }
  }
}

Reconstruction ModelWithEveryCameraModel() {
  Reconstruction r = MakePlaneModel();
  for (const CameraModelInfo& info : CameraModels()) {
    Camera camera;
    camera.camera_id = 100 + info.id;
    camera.model_id = info.id;
    camera.width = 640 + info.id;
    camera.height = 480;
    for (int k = 0; k < info.num_params; ++k) camera.params.push_back(0.1 * k + 1.0 / 3.0);
    r.cameras[camera.camera_id] = camera;
  }
  return r;
}

TEST(CameraModels, IdsNamesAndParameterCounts) {
  const std::vector<CameraModelInfo>& models = CameraModels();
  ASSERT_EQ(models.size(), 18u);
  const int kNumParams[18] = {3, 4, 4, 5, 8, 8, 12, 5, 4, 5, 12, 16, 4, 5, 3, 4, 6, 2};
  std::set<std::string> names;
  for (int id = 0; id < 18; ++id) {
    const CameraModelInfo& info = CameraModelById(id);
    EXPECT_EQ(info.id, id);
    EXPECT_EQ(info.num_params, kNumParams[id]) << info.name;
    EXPECT_EQ(CameraModelByName(info.name).id, id);
    names.insert(info.name);
  }
  EXPECT_EQ(names.size(), 18u);
  EXPECT_STREQ(CameraModelById(1).name, "PINHOLE");
  EXPECT_STREQ(CameraModelById(10).name, "THIN_PRISM_FISHEYE");
  EXPECT_STREQ(CameraModelById(17).name, "EQUIRECTANGULAR");
  EXPECT_THROW(CameraModelById(18), Error);
  EXPECT_THROW(CameraModelById(-1), Error);
  EXPECT_THROW(CameraModelByName("PINHOLES"), Error);
}

TEST(Camera, CalibrationMatrix) {
  Camera camera;
  camera.model_id = 0;
  camera.params = {100, 32, 24};
  Eigen::Matrix3d K = camera.CalibrationMatrix();
  EXPECT_EQ(K(0, 0), 100);
  EXPECT_EQ(K(1, 1), 100);
  EXPECT_EQ(K(0, 2), 32);
  EXPECT_EQ(K(1, 2), 24);
  camera.model_id = 1;
  camera.params = {100, 90, 31, 23};
  K = camera.CalibrationMatrix();
  EXPECT_EQ(K(1, 1), 90);
  EXPECT_EQ(K(1, 2), 23);
  // A perspective model without distortion, as colmap image_undistorter copies it through.
  camera.model_id = 4;  // OPENCV
  camera.params = {100, 90, 31, 23, 0, 0, 0, 0};
  EXPECT_TRUE(camera.IsPinhole());
  K = camera.CalibrationMatrix();
  EXPECT_EQ(K(0, 0), 100);
  EXPECT_EQ(K(1, 1), 90);
  EXPECT_EQ(K(0, 2), 31);
  EXPECT_EQ(K(1, 2), 23);
  camera.model_id = 2;  // SIMPLE_RADIAL
  camera.params = {100, 32, 24, 0};
  K = camera.CalibrationMatrix();
  EXPECT_EQ(K(1, 1), 100);
  EXPECT_EQ(K(0, 2), 32);
  EXPECT_EQ(K(1, 2), 24);
  // With distortion, or a fisheye model (not perspective even without it): refused.
  camera.params = {100, 32, 24, 0.01};
  ExpectErrorMentions([&] { camera.CalibrationMatrix(); },
                      {"SIMPLE_RADIAL", "with distortion", "image_undistorter"});
  camera.model_id = 4;
  camera.params = {100, 90, 31, 23, 0, 0, 1e-4, 0};
  ExpectErrorMentions([&] { camera.CalibrationMatrix(); }, {"OPENCV", "image_undistorter"});
  camera.model_id = 5;  // OPENCV_FISHEYE
  camera.params = {100, 90, 31, 23, 0, 0, 0, 0};
  EXPECT_FALSE(camera.IsPinhole());
}

TEST(Reconstruction, BinaryRoundTripThroughMemory) {
  const Reconstruction model = ModelWithEveryCameraModel();
  std::stringstream cameras, images, points;
  WriteCamerasBinary(model, cameras);
  WriteImagesBinary(model, images);
  WritePoints3DBinary(model, points);
  Reconstruction read;
  ReadCamerasBinary(cameras, "cameras", &read);
  ReadImagesBinary(images, "images", &read);
  ReadPoints3DBinary(points, "points", &read);
  ExpectModelsEqual(model, read);
  EXPECT_EQ(read.image_order, model.image_order);
}

TEST(Reconstruction, TextRoundTripThroughMemoryIsExact) {
  Reconstruction model = ModelWithEveryCameraModel();
  // Values that need all 17 digits.
  model.images.begin()->second.cam_from_world_translation = Eigen::Vector3d(0.1, 1.0 / 3, -2e-7);
  model.points3D.begin()->second.xyz = Eigen::Vector3d(M_PI, -M_E, 1e10 / 7);
  std::stringstream cameras, images, points;
  WriteCamerasText(model, cameras);
  WriteImagesText(model, images);
  WritePoints3DText(model, points);
  for (const std::string& text : {cameras.str(), images.str(), points.str()}) {
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line)) {
      if (line.empty() || line[0] == '#') continue;
      EXPECT_EQ(line.find("  "), std::string::npos) << "COLMAP 3.8 needs single spaces";
      EXPECT_NE(line.back(), ' ');
    }
  }
  Reconstruction read;
  ReadCamerasText(cameras, "cameras", &read);
  ReadImagesText(images, "images", &read);
  ReadPoints3DText(points, "points", &read);
  ExpectModelsEqual(model, read);
}

TEST(Reconstruction, TextImagesHaveTwoLinesEvenWithoutPoints) {
  Reconstruction model = MakePlaneModel();
  model.images.at(2).points2D.clear();
  std::stringstream images;
  WriteImagesText(model, images);
  Reconstruction read;
  ReadImagesText(images, "images", &read);
  ASSERT_EQ(read.images.size(), 3u);
  EXPECT_TRUE(read.images.at(2).points2D.empty());
  EXPECT_EQ(read.images.at(3).points2D.size(), model.images.at(3).points2D.size());
}

TEST(Reconstruction, BinarySizesMatchColmap) {
  // colmap-formats.md 4.4: 2 PINHOLE cameras = 120 B; images a.png, b.png with 6 keypoints
  // each = 452 B; 5 points with tracks of length 2 = 343 B.
  testing_util::PlaneModelOptions options;
  options.centres = {{0, 0, 0}, {0.5, 0, 0}};
  options.num_points = 5;
  Reconstruction model = MakePlaneModel(options);
  for (auto& [id, image] : model.images) image.points2D.resize(6);
  std::stringstream cameras, images, points;
  WriteCamerasBinary(model, cameras);
  WriteImagesBinary(model, images);
  WritePoints3DBinary(model, points);
  EXPECT_EQ(cameras.str().size(), 120u);
  EXPECT_EQ(images.str().size(), 452u);
  EXPECT_EQ(points.str().size(), 343u);
}

TEST(Reconstruction, TruncatedBinaryThrowsNamingTheFile) {
  const Reconstruction model = MakePlaneModel();
  std::stringstream cameras, images, points;
  WriteCamerasBinary(model, cameras);
  WriteImagesBinary(model, images);
  WritePoints3DBinary(model, points);
  using Reader = void (*)(std::istream&, const std::string&, Reconstruction*);
  const std::vector<std::pair<std::string, Reader>> cases = {
      {cameras.str(), ReadCamerasBinary},
      {images.str(), ReadImagesBinary},
      {points.str(), ReadPoints3DBinary}};
  for (const auto& [bytes, reader] : cases) {
    // Every proper prefix is truncated.
    for (size_t n = 0; n < bytes.size(); n += 7) {
      std::istringstream in(bytes.substr(0, n));
      Reconstruction r;
      ExpectErrorMentions([&] { reader(in, "some/model.bin", &r); },
                          {"some/model.bin", "truncated"});
    }
    // One byte too many.
    std::istringstream in(bytes + "x");
    Reconstruction r;
    ExpectErrorMentions([&] { reader(in, "some/model.bin", &r); },
                        {"some/model.bin", "unexpected bytes"});
  }
}

TEST(Reconstruction, HugeCountIsTruncationNotAllocation) {
  std::string bytes(8, '\xff');  // num_points3D = 2^64 - 1
  std::istringstream in(bytes);
  Reconstruction r;
  ExpectErrorMentions([&] { ReadPoints3DBinary(in, "points3D.bin", &r); },
                      {"points3D.bin", "truncated"});
}

TEST(Reconstruction, CorruptedBinaryEitherReadsOrThrows) {
  // Random byte changes (fixed seed): every outcome is a model or a hairmvs::Error, never a
  // crash or a runaway allocation.
  const Reconstruction model = MakePlaneModel();
  std::stringstream cameras, images, points;
  WriteCamerasBinary(model, cameras);
  WriteImagesBinary(model, images);
  WritePoints3DBinary(model, points);
  using Reader = void (*)(std::istream&, const std::string&, Reconstruction*);
  const std::vector<std::pair<std::string, Reader>> cases = {
      {cameras.str(), ReadCamerasBinary},
      {images.str(), ReadImagesBinary},
      {points.str(), ReadPoints3DBinary}};
  std::mt19937 rng(11);
  int num_errors = 0;
  for (const auto& [bytes, reader] : cases) {
    for (int trial = 0; trial < 200; ++trial) {
      std::string corrupted = bytes;
      std::uniform_int_distribution<size_t> pos(0, corrupted.size() - 1);
      for (int k = 0; k < 3; ++k) corrupted[pos(rng)] = static_cast<char>(rng() & 0xff);
      std::istringstream in(corrupted);
      Reconstruction r;
      try {
        reader(in, "fuzz.bin", &r);
      } catch (const Error& e) {
        ++num_errors;
        EXPECT_NE(std::string(e.what()).find("fuzz.bin"), std::string::npos) << e.what();
      }
    }
  }
  EXPECT_GT(num_errors, 0);
}

TEST(Reconstruction, UnknownModelIdInBinary) {
  Reconstruction model = MakePlaneModel();
  std::stringstream cameras;
  WriteCamerasBinary(model, cameras);
  std::string bytes = cameras.str();
  const int32_t bad_id = 42;
  std::memcpy(&bytes[8 + 4], &bad_id, 4);  // first camera's model_id
  std::istringstream in(bytes);
  Reconstruction r;
  ExpectErrorMentions([&] { ReadCamerasBinary(in, "cameras.bin", &r); },
                      {"cameras.bin", "Unknown camera model id 42"});
}

TEST(Reconstruction, BadTextInputThrowsNamingFileAndLine) {
  struct Case {
    std::string text;
    void (*reader)(std::istream&, const std::string&, Reconstruction*);
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"1 PINHOLE 64 48 50 50 32\n", ReadCamerasText, "3 parameters, expected 4"},
      {"1 FANCY 64 48 50 50 32 24\n", ReadCamerasText, "Unknown camera model name"},
      {"1 PINHOLE 64  48 50 50 32 24\n", ReadCamerasText, "doubled space"},
      {"1 PINHOLE 64\t48 50 50 32 24\n", ReadCamerasText, "tab"},
      {"1 PINHOLE 64 4x8 50 50 32 24\n", ReadCamerasText, "HEIGHT"},
      {"# c\n1 1 0 0 0 0 0 0 1 a.png\n", ReadImagesText, "no second line"},
      {"1 1 0 0 0 0 0 0 1 a b.png\n\n", ReadImagesText, "10 tokens"},
      {"1 1 0 0 0 0 0 0 1 a.png\n1.0 2.0\n", ReadImagesText, "multiple of 3"},
      {"1 1 0 0 0 0 0 0 1 a.png\n# no\n", ReadImagesText, "comment"},
      {"1 0 0 0 0 0 0 0 1 a.png\n\n", ReadImagesText, "quaternion"},
      {"1 1 0 0 0 1e400 0 0 1 a.png\n\n", ReadImagesText, "translation from '1e400'"},
      {"1 1 2 3 255 0 0 0.5 1\n", ReadPoints3DText, "tokens"},
      {"1 1 2 3 256 0 0 0.5\n", ReadPoints3DText, "outside 0-255"},
  };
  for (const Case& c : cases) {
    std::istringstream in(c.text);
    Reconstruction r;
    ExpectErrorMentions([&] { c.reader(in, "sparse/x.txt", &r); },
                        {"sparse/x.txt:", c.expected});
  }
}

TEST(Reconstruction, TextToleratesCrlfTrailingSpacesAndComments) {
  std::istringstream cameras("# comment\r\n1 PINHOLE 64 48 50 50 32 24 \r\n\r\n");
  std::istringstream images("# c\n\n1 1 0 0 0 0 0 0 1 a.png\r\n1.5 2.5 -1 3 4 7\r\n");
  std::istringstream points("7 1 2 3 10 20 30 0.5 1 1\n");
  Reconstruction r;
  ReadCamerasText(cameras, "c", &r);
  ReadImagesText(images, "i", &r);
  ReadPoints3DText(points, "p", &r);
  ASSERT_EQ(r.cameras.size(), 1u);
  EXPECT_EQ(r.cameras.at(1).params[3], 24);
  ASSERT_EQ(r.images.at(1).points2D.size(), 2u);
  EXPECT_EQ(r.images.at(1).points2D[0].point3D_id, kInvalidPoint3DId);
  EXPECT_EQ(r.images.at(1).points2D[1].point3D_id, 7u);
  EXPECT_EQ(r.points3D.at(7).rgb[2], 30);
  EXPECT_EQ(r.points3D.at(7).track[0].point2D_idx, 1u);
}

// COLMAP writes what it holds with 17 digits, a denormal too (9.9999999999999694e-311), and
// reads it back; so do we. strtod flags the underflow as a range error all the same.
TEST(Reconstruction, TextReadsDenormalNumbers) {
  std::istringstream images("1 1 0 0 0 9.9999999999999694e-311 0 0 1 a.png\n1e-320 2.5 -1\n");
  Reconstruction r;
  ReadImagesText(images, "images.txt", &r);
  EXPECT_GT(r.images.at(1).t().x(), 0.0);
  EXPECT_LT(r.images.at(1).t().x(), 1e-300);
  EXPECT_GT(r.images.at(1).points2D.at(0).xy.x(), 0.0);
}

TEST(Reconstruction, ImageOrderFollowsTheFile) {
  std::istringstream images(
      "2 1 0 0 0 0 0 0 1 b.png\n\n1 1 0 0 0 0 0 0 1 a.png\n\n");
  Reconstruction r;
  ReadImagesText(images, "images.txt", &r);
  EXPECT_EQ(r.image_order, (std::vector<uint32_t>{2, 1}));
  r.SortImageOrder();
  EXPECT_EQ(r.image_order, (std::vector<uint32_t>{1, 2}));
}

TEST(Reconstruction, FolderRoundTripAndFormatChoice) {
  const std::string dir = MakeTestDir("folder");
  const Reconstruction model = ModelWithEveryCameraModel();
  WriteReconstruction(model, JoinPaths(dir, "bin"), ModelFormat::kBinary);
  WriteReconstruction(model, JoinPaths(dir, "txt"), ModelFormat::kText);
  ExpectModelsEqual(model, ReadReconstruction(JoinPaths(dir, "bin")));
  ExpectModelsEqual(model, ReadReconstruction(JoinPaths(dir, "txt")));

  // Both present: binary wins (COLMAP's rule); rigs/frames files are ignored.
  const std::string both = JoinPaths(dir, "both");
  WriteReconstruction(model, both, ModelFormat::kBinary);
  // (A text model is not written over a binary one: its files are copied there.)
  const std::string other = JoinPaths(dir, "other");
  WriteReconstruction(MakePlaneModel(), other, ModelFormat::kText);
  for (const char* name : {"cameras.txt", "images.txt", "points3D.txt"}) {
    CopyFileAtomically(JoinPaths(other, name), JoinPaths(both, name));
  }
  WriteFileAtomically(JoinPaths(both, "rigs.bin"), [](std::ostream& out) { out << "junk"; });
  WriteFileAtomically(JoinPaths(both, "frames.txt"), [](std::ostream& out) { out << "junk"; });
  EXPECT_EQ(ReadReconstruction(both).cameras.size(), model.cameras.size());
}

// A model's three files are one unit: an image name that cannot be written (images.* is the
// second file) leaves the old model whole, not a new cameras file beside the old images file.
TEST(Reconstruction, FailedWriteLeavesTheOldModel) {
  for (const ModelFormat format : {ModelFormat::kBinary, ModelFormat::kText}) {
    const bool binary = format == ModelFormat::kBinary;
    const std::string dir = MakeTestDir(binary ? "unit_bin" : "unit_txt");
    const Reconstruction model = MakePlaneModel();
    WriteReconstruction(model, dir, format);
    const std::string ext = binary ? ".bin" : ".txt";
    std::vector<std::string> old_bytes;
    for (const char* name : {"cameras", "images", "points3D"}) {
      old_bytes.push_back(ReadTextFile(JoinPaths(dir, name + ext)));
    }
    Reconstruction changed = ModelWithEveryCameraModel();
    changed.images.begin()->second.name = "my photo.png";
    ExpectErrorMentions([&] { WriteReconstruction(changed, dir, format); },
                        {"my photo.png", "no whitespace"});
    int i = 0;
    for (const char* name : {"cameras", "images", "points3D"}) {
      EXPECT_TRUE(ReadTextFile(JoinPaths(dir, name + ext)) == old_bytes[i++])
          << name << ext << " was replaced";
    }
    EXPECT_EQ(testing_util::NumEntriesIn(dir), 3);
    ExpectModelsEqual(model, ReadReconstruction(dir));
  }
}

// A text model written where a binary one is would be ignored (readers prefer binary): it is
// refused, naming the folder and why, and the binary model is left as it is.
TEST(Reconstruction, TextModelOverABinaryOneIsRefused) {
  const std::string dir = MakeTestDir("text_over_binary");
  const Reconstruction model = MakePlaneModel();
  WriteReconstruction(model, dir, ModelFormat::kBinary);
  const std::string old_images = ReadTextFile(JoinPaths(dir, "images.bin"));
  ExpectErrorMentions([&] { WriteReconstruction(model, dir, ModelFormat::kText); },
                      {"text model", dir, "cameras.bin, images.bin and points3D.bin"});
  EXPECT_TRUE(ReadTextFile(JoinPaths(dir, "images.bin")) == old_images);
  EXPECT_EQ(testing_util::NumEntriesIn(dir), 3);
  // A binary model over a text one takes over (the stale text files are ignored), and a text
  // model beside an incomplete binary one is read.
  const std::string text_dir = MakeTestDir("binary_over_text");
  WriteReconstruction(MakePlaneModel(), text_dir, ModelFormat::kText);
  WriteReconstruction(ModelWithEveryCameraModel(), text_dir, ModelFormat::kBinary);
  ExpectModelsEqual(ModelWithEveryCameraModel(), ReadReconstruction(text_dir));
  std::filesystem::remove(JoinPaths(dir, "points3D.bin"));
  WriteReconstruction(ModelWithEveryCameraModel(), dir, ModelFormat::kText);
  ExpectModelsEqual(ModelWithEveryCameraModel(), ReadReconstruction(dir));
}

TEST(Reconstruction, MissingModelFiles) {
  const std::string dir = MakeTestDir("missing");
  ExpectErrorMentions([&] { ReadReconstruction(JoinPaths(dir, "nope")); },
                      {"nope", "Missing sparse model folder"});
  const std::string partial = JoinPaths(dir, "partial");
  WriteReconstruction(MakePlaneModel(), JoinPaths(partial, "0"), ModelFormat::kBinary);
  WriteFileAtomically(JoinPaths(partial, "cameras.bin"), [](std::ostream& out) { out << "x"; });
  ExpectErrorMentions([&] { ReadReconstruction(partial); },
                      {partial, "missing images.bin and points3D.bin (cameras.bin is there",
                       "sub-folder 0/"});
  // None of the six files: COLMAP's message, and the hint.
  std::filesystem::remove(JoinPaths(partial, "cameras.bin"));
  ExpectErrorMentions([&] { ReadReconstruction(partial); },
                      {partial, "do not exist", "sub-folder 0/"});
}

// A model with one of its files deleted names that file and the two that are there (not "files
// do not exist"), in either format.
TEST(Reconstruction, MissingOneModelFileIsNamed) {
  for (const ModelFormat format : {ModelFormat::kBinary, ModelFormat::kText}) {
    const std::string ext = format == ModelFormat::kBinary ? ".bin" : ".txt";
    const std::string dir = MakeTestDir("missing_one" + ext);
    WriteReconstruction(MakePlaneModel(), dir, format);
    std::filesystem::remove(JoinPaths(dir, "cameras" + ext));
    const std::string message = testing_util::ErrorOf([&] { ReadReconstruction(dir); });
    EXPECT_NE(message.find(dir + ": missing cameras" + ext + " (images" + ext +
                           " and points3D" + ext + " are there"),
              std::string::npos)
        << message;
    EXPECT_EQ(message.find("do not exist"), std::string::npos) << message;
  }
}

TEST(Reconstruction, ImageWithUnknownCameraIsAnError) {
  const std::string dir = MakeTestDir("unknown_camera");
  Reconstruction model = MakePlaneModel();
  model.images.at(2).camera_id = 99;
  WriteReconstruction(model, dir, ModelFormat::kText);
  ExpectErrorMentions([&] { ReadReconstruction(dir); }, {"images.txt", "camera 99"});
}

TEST(Reconstruction, InconsistentTracksAreNamedButRead) {
  Reconstruction model = MakePlaneModel();
  EXPECT_EQ(DescribeTrackInconsistencies(model, "p", "i"), "");
  model.points3D.at(3).track[0].image_id = 99;
  model.points3D.at(4).track[1].point2D_idx = 1000;
  model.points3D.at(5).track[2].point2D_idx = 2000;
  model.points3D.erase(7);  // its keypoints in all three images now name a missing point
  const std::string message = DescribeTrackInconsistencies(model, "p.bin", "i.bin");
  // 40 points seen by 3 images, less the 3 elements of the erased point.
  const std::vector<std::string> parts = {
      "p.bin: 1 of 117 track elements name an image that is not in the model "
      "(first: point 3 -> image 99).",
      "p.bin: 2 of 117 track elements name a keypoint beyond their image's keypoints "
      "(first: point 4 -> keypoint 1000 of image 2 (b.png), which has 40).",
      "i.bin: 3 of 120 triangulated keypoints name a 3D point that is not in the model "
      "(first: image 1 (a.png) -> point 7)."};
  for (const std::string& part : parts) {
    EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
  }
  // Such a model still reads, as it was written.
  const std::string dir = MakeTestDir("inconsistent_tracks");
  WriteReconstruction(model, dir, ModelFormat::kBinary);
  ExpectModelsEqual(model, ReadReconstruction(dir));
}

// Writes `model` as a text model in a fresh folder `name`, lets `edit` change the text of
// `file` (cameras.txt, images.txt), and returns the error of reading it back.
template <typename Edit>
std::string ErrorOfEditedTextModel(const std::string& name, const Reconstruction& model,
                                   const std::string& file, Edit&& edit) {
  const std::string dir = MakeTestDir(name);
  WriteReconstruction(model, dir, ModelFormat::kText);
  std::string text = ReadTextFile(JoinPaths(dir, file));
  edit(&text);
  WriteFileAtomically(JoinPaths(dir, file), [&](std::ostream& out) { out << text; });
  return testing_util::ErrorOf([&] { ReadReconstruction(dir); });
}

// Replaces the first occurrence of `from` in `text` (the test fails when there is none).
void ReplaceOnce(std::string* text, const std::string& from, const std::string& to) {
  const size_t pos = text->find(from);
  ASSERT_NE(pos, std::string::npos) << from;
  text->replace(pos, from.size(), to);
}

// The line number (1-based) of the line of `text` that starts with `prefix`.
int LineStartingWith(const std::string& text, const std::string& prefix) {
  std::istringstream lines(text);
  std::string line;
  for (int n = 1; std::getline(lines, line); ++n) {
    if (line.rfind(prefix, 0) == 0) return n;
  }
  return -1;
}

// COLMAP requires unique image names (depth maps are named after them); a second image with a
// name already taken is refused, naming both ids (and, in text, the line of the second).
TEST(Reconstruction, DuplicateImageNamesAreRefused) {
  Reconstruction model = MakePlaneModel();
  model.images.at(3).name = "a.png";  // images 1 and 3
  std::stringstream bytes;
  WriteImagesBinary(model, bytes);
  Reconstruction r;
  std::string message = testing_util::ErrorOf([&] { ReadImagesBinary(bytes, "images.bin", &r); });
  EXPECT_NE(message.find("images.bin: images 1 and 3 both have the name a.png"),
            std::string::npos)
      << message;

  std::stringstream text;
  WriteImagesText(model, text);
  const int line = LineStartingWith(text.str(), "3 ");
  ASSERT_GT(line, 0);
  Reconstruction t;
  message = testing_util::ErrorOf([&] { ReadImagesText(text, "sparse/images.txt", &t); });
  EXPECT_NE(message.find("sparse/images.txt:" + std::to_string(line) +
                         ": images 1 and 3 both have the name a.png"),
            std::string::npos)
      << message;

  // Through the folder reader too.
  const std::string dir = MakeTestDir("duplicate_names");
  WriteReconstruction(model, dir, ModelFormat::kBinary);
  message = testing_util::ErrorOf([&] { ReadReconstruction(dir); });
  EXPECT_NE(message.find(JoinPaths(dir, "images.bin") + ": images 1 and 3"), std::string::npos)
      << message;
}

// A width or height of 0 (a CHECK on an empty map later) or beyond kMaxCameraSizePx (an int
// that turns negative) is refused at reading, naming the file, line and camera.
TEST(Reconstruction, CameraSizeOutsideLimitsIsRefused) {
  const Reconstruction model = MakePlaneModel();
  // Text: width 0, height 0. The first camera's line is "1 PINHOLE 64 48 ...".
  std::string message = ErrorOfEditedTextModel(
      "camera_width_0", model, "cameras.txt",
      [](std::string* text) { ReplaceOnce(text, "\n1 PINHOLE 64 48 ", "\n1 PINHOLE 0 48 "); });
  EXPECT_NE(message.find("cameras.txt:4: camera 1: width 0 is outside 1..1000000"),
            std::string::npos)
      << message;
  message = ErrorOfEditedTextModel(
      "camera_height_0", model, "cameras.txt",
      [](std::string* text) { ReplaceOnce(text, "\n2 PINHOLE 64 48 ", "\n2 PINHOLE 64 0 "); });
  EXPECT_NE(message.find("cameras.txt:5: camera 2: height 0 is outside 1..1000000"),
            std::string::npos)
      << message;
  // Binary: a height above INT_MAX (uint64 in the file).
  Reconstruction huge = model;
  huge.cameras.at(2).height = uint64_t{1} << 31;
  const std::string dir = MakeTestDir("camera_height_huge");
  WriteReconstruction(huge, dir, ModelFormat::kBinary);
  message = testing_util::ErrorOf([&] { ReadReconstruction(dir); });
  EXPECT_NE(message.find(JoinPaths(dir, "cameras.bin") + ": camera 2: height 2147483648 is "
                                                         "outside 1..1000000"),
            std::string::npos)
      << message;
  // The largest size allowed reads.
  huge.cameras.at(2).height = kMaxCameraSizePx;
  WriteReconstruction(huge, dir, ModelFormat::kBinary);
  EXPECT_EQ(ReadReconstruction(dir).cameras.at(2).height, kMaxCameraSizePx);
}

// A parameter that is nan or inf (strtod parses both) is refused for any model, and a focal
// length that is not > 0 for every model: the stereo would write empty maps over good ones.
TEST(Reconstruction, NonFiniteCameraParametersAndBadFocalLengthsAreRefused) {
  const Reconstruction model = MakePlaneModel();  // "1 PINHOLE 64 48 50 50 32 24"
  struct Case {
    std::string from, to, expected;
  };
  const std::vector<Case> cases = {
      {" 64 48 50 50 32 24", " 64 48 50 nan 32 24", "camera 1: parameter 2 (fy of PINHOLE) is nan"},
      {" 64 48 50 50 32 24", " 64 48 50 50 inf 24", "camera 1: parameter 3 (cx of PINHOLE) is inf"},
      {" 64 48 50 50 32 24", " 64 48 50 50 32 -inf",
       "camera 1: parameter 4 (cy of PINHOLE) is -inf"},
      {" 64 48 50 50 32 24", " 64 48 0 50 32 24",
       "camera 1: focal length fx (parameter 1 of PINHOLE) is 0; it must be > 0"},
      {" 64 48 50 50 32 24", " 64 48 50 -50 32 24",
       "camera 1: focal length fy (parameter 2 of PINHOLE) is -50; it must be > 0"},
      {"1 PINHOLE 64 48 50 50 32 24", "1 SIMPLE_PINHOLE 64 48 -1 32 24",
       "camera 1: focal length f (parameter 1 of SIMPLE_PINHOLE) is -1"},
      {"1 PINHOLE 64 48 50 50 32 24", "1 SIMPLE_RADIAL 64 48 0 32 24 0.1",
       "camera 1: focal length f (parameter 1 of SIMPLE_RADIAL)"},
      {"1 PINHOLE 64 48 50 50 32 24", "1 OPENCV 64 48 50 0 32 24 0 0 0 0",
       "camera 1: focal length fy (parameter 2 of OPENCV)"},
      {"1 PINHOLE 64 48 50 50 32 24", "1 OPENCV 64 48 50 50 32 24 0 nan 0 0",
       "camera 1: parameter 6 (k2 of OPENCV) is nan"},
      {"1 PINHOLE 64 48 50 50 32 24", "1 FULL_OPENCV 64 48 50 -2 32 24 0 0 0 0 0 0 0 0",
       "camera 1: focal length fy (parameter 2 of FULL_OPENCV)"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string message = ErrorOfEditedTextModel(
        "camera_params_" + std::to_string(i++), model, "cameras.txt",
        [&](std::string* text) { ReplaceOnce(text, c.from, c.to); });
    EXPECT_NE(message.find("cameras.txt:4: " + c.expected), std::string::npos)
        << c.to << ": " << message;
  }
  // Every model with a focal length refuses 0 there, in binary too.
  for (const CameraModelInfo& info : CameraModels()) {
    for (int k = 0; k < info.num_focal_params; ++k) {
      Reconstruction r = model;
      Camera& camera = r.cameras.at(1);
      camera.model_id = info.id;
      camera.params.assign(info.num_params, 10.0);
      camera.params[k] = 0.0;
      std::stringstream bytes;
      WriteCamerasBinary(r, bytes);
      Reconstruction read;
      const std::string message =
          testing_util::ErrorOf([&] { ReadCamerasBinary(bytes, "cameras.bin", &read); });
      EXPECT_NE(message.find("cameras.bin: camera 1: focal length"), std::string::npos)
          << info.name << ": " << message;
    }
    // A nan in the last parameter, whatever it is.
    Reconstruction r = model;
    Camera& camera = r.cameras.at(1);
    camera.model_id = info.id;
    camera.params.assign(info.num_params, 10.0);
    camera.params.back() = std::nan("");
    std::stringstream bytes;
    WriteCamerasBinary(r, bytes);
    Reconstruction read;
    const std::string message =
        testing_util::ErrorOf([&] { ReadCamerasBinary(bytes, "cameras.bin", &read); });
    EXPECT_NE(message.find("cameras.bin: camera 1: parameter " + std::to_string(info.num_params)),
              std::string::npos)
        << info.name << ": " << message;
    EXPECT_NE(message.find("is nan"), std::string::npos) << info.name << ": " << message;
  }
}

// A translation of nan or inf makes every depth map of that view empty and every source view
// of it useless; it is refused, naming the image (binary) or the line (text).
TEST(Reconstruction, NonFiniteTranslationIsRefused) {
  const Reconstruction model = MakePlaneModel();
  for (const double bad : {std::nan(""), std::numeric_limits<double>::infinity()}) {
    Reconstruction r = model;
    r.images.at(2).cam_from_world_translation.z() = bad;
    std::stringstream bytes;
    WriteImagesBinary(r, bytes);
    Reconstruction read = model;
    read.images.clear();
    const std::string message =
        testing_util::ErrorOf([&] { ReadImagesBinary(bytes, "images.bin", &read); });
    EXPECT_NE(message.find("images.bin: image 2: translation ("), std::string::npos) << message;
    EXPECT_NE(message.find("is not finite"), std::string::npos) << message;
  }
  std::string text;
  const std::string message =
      ErrorOfEditedTextModel("translation_nan", model, "images.txt", [&](std::string* t) {
        const size_t line = t->find("\n2 ");
        ASSERT_NE(line, std::string::npos);
        // IMAGE_ID QW QX QY QZ TX TY TZ: the 8th token becomes nan.
        size_t pos = line + 1;
        for (int k = 0; k < 7; ++k) pos = t->find(' ', pos) + 1;
        t->replace(pos, t->find(' ', pos) - pos, "nan");
        text = *t;
      });
  const int line = LineStartingWith(text, "2 ");
  EXPECT_NE(message.find("images.txt:" + std::to_string(line) + ": translation ("),
            std::string::npos)
      << message;
  EXPECT_NE(message.find(", nan) is not finite"), std::string::npos) << message;
}

// COLMAP's mapper's test of a calibration (HasBogusParams): each camera outside it is named
// with what is wrong; a model that passes gets no warning (and still reads either way).
TEST(Reconstruction, ImplausibleCalibrationsAreNamed) {
  Reconstruction model = MakePlaneModel();  // "1 PINHOLE 64 48 50 50 32 24"
  EXPECT_EQ(DescribeImplausibleCameras(model, "cameras.bin"), "");
  // The limits themselves pass: focal 0.1 and 10 times 64 px, the principal point on the edge.
  model.cameras.at(1).params = {6.4, 640, 64, 0};
  EXPECT_EQ(DescribeImplausibleCameras(model, "cameras.bin"), "");
  model.cameras.at(1).params = {6.3, 50, 32, 48.5};
  Camera second = model.cameras.at(1);
  second.camera_id = 7;
  second.model_id = CameraModelByName("SIMPLE_RADIAL").id;
  second.params = {50, 1e30, 24, 0.01};
  model.cameras[7] = second;
  const std::string message = DescribeImplausibleCameras(model, "sparse/cameras.bin");
  for (const std::string part :
       {"sparse/cameras.bin: camera 1 (PINHOLE, 64 x 48 px): fx 6.3 is 0.0984375 times the "
        "larger side, the principal point (32, 48.5) lies outside the image; camera 7 "
        "(SIMPLE_RADIAL, 64 x 48 px): the principal point (1e+30, 24) lies outside the image.",
        "unless its --Mapper.min/max_focal_length_ratio were changed"}) {
    EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
  }
  const std::string dir = MakeTestDir("implausible_calibration");
  WriteReconstruction(model, dir, ModelFormat::kBinary);
  // Said once per folder however often a command reads it.
  ::testing::internal::CaptureStderr();
  ExpectModelsEqual(model, ReadReconstruction(dir));
  std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("camera 7 (SIMPLE_RADIAL"), std::string::npos) << log;
  ::testing::internal::CaptureStderr();
  ExpectModelsEqual(model, ReadReconstruction(dir));
  log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(log.find("camera 7 (SIMPLE_RADIAL"), std::string::npos) << log;
}

TEST(CameraModels, FocalLengthsAndParameterNames) {
  EXPECT_EQ(CameraModelByName("SIMPLE_PINHOLE").num_focal_params, 1);
  EXPECT_EQ(CameraModelByName("PINHOLE").num_focal_params, 2);
  EXPECT_EQ(CameraModelByName("RADIAL").num_focal_params, 1);
  EXPECT_EQ(CameraModelByName("FULL_OPENCV").num_focal_params, 2);
  EXPECT_EQ(CameraModelByName("EQUIRECTANGULAR").num_focal_params, 0);
  for (const CameraModelInfo& info : CameraModels()) {
    // params_info has one name per parameter; the focal lengths lead.
    EXPECT_NE(CameraParamName(info, info.num_params - 1), "?") << info.name;
    EXPECT_EQ(CameraParamName(info, info.num_params), "?") << info.name;
    for (int k = 0; k < info.num_focal_params; ++k) {
      EXPECT_EQ(CameraParamName(info, k)[0], 'f') << info.name;
    }
    EXPECT_NE(CameraParamName(info, info.num_focal_params)[0], 'f') << info.name;
  }
  EXPECT_EQ(CameraParamName(CameraModelByName("OPENCV"), 7), "p2");
}

}  // namespace
}  // namespace hairmvs
