#include "colmap_ext/reconstruction.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
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
  camera.model_id = 4;
  camera.params.assign(8, 0.0);
  ExpectErrorMentions([&] { camera.CalibrationMatrix(); }, {"OPENCV", "image_undistorter"});
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
                      {partial, "do not exist", "sub-folder 0/"});
}

TEST(Reconstruction, ImageWithUnknownCameraIsAnError) {
  const std::string dir = MakeTestDir("unknown_camera");
  Reconstruction model = MakePlaneModel();
  model.images.at(2).camera_id = 99;
  WriteReconstruction(model, dir, ModelFormat::kText);
  ExpectErrorMentions([&] { ReadReconstruction(dir); }, {"images.txt", "camera 99"});
}

}  // namespace
}  // namespace hairmvs
