#include "colmap_ext/workspace.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "colmap_ext/test_util.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace hairmvs {
namespace {

using testing_util::MakePlaneModel;
using testing_util::ErrorOf;
using testing_util::MakeTestDir;
using testing_util::WriteTestWorkspace;

TEST(Workspace, ReadsLayoutAndPaths) {
  const std::string dir = MakeTestDir("ws");
  const Reconstruction model = MakePlaneModel();
  WriteTestWorkspace(dir, model);
  std::filesystem::create_directories(JoinPaths(dir, "masks"));
  cv::imwrite(JoinPaths(dir, "masks", "b.png.png"), cv::Mat(48, 64, CV_8U, cv::Scalar(255)));

  const Workspace ws = Workspace::Read(dir);
  EXPECT_EQ(ws.ImageNames(), (std::vector<std::string>{"a.png", "b.png", "c.png"}));
  EXPECT_EQ(ws.ImageIdx("c.png"), 2);
  EXPECT_THROW(ws.ImageIdx("d.png"), Error);
  // --image_names: every image when none is given, those given in their order, an unknown one
  // or one given twice refused by name.
  EXPECT_EQ(ws.SelectImages({}), ws.ImageNames());
  EXPECT_EQ(ws.SelectImages({"c.png", "a.png"}), (std::vector<std::string>{"c.png", "a.png"}));
  EXPECT_NE(ErrorOf([&] { ws.SelectImages({"a.png", "d.png"}); })
                .find("Image with name `d.png` (--image_names) does not exist in workspace"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ws.SelectImages({"a.png", "b.png", "a.png"}); })
                .find("Image `a.png` is given twice"),
            std::string::npos);
  EXPECT_EQ(ws.ImageByName("b.png").image_id, 2u);
  EXPECT_EQ(ws.CameraOf("b.png").CalibrationMatrix()(0, 0), 50.0);
  EXPECT_NO_THROW(ws.RequireUndistortedCameras());
  const FloatMap gray = ws.ReadViewGray("a.png");
  EXPECT_EQ(gray.Width(), 64);
  EXPECT_EQ(ws.ReadViewRgb("a.png").Channels(), 3);
  // An image resized after the undistorter no longer fits its camera: named, with both sizes.
  cv::imwrite(JoinPaths(dir, "images", "c.png"), cv::Mat(24, 32, CV_8U, cv::Scalar(128)));
  const std::string resized = ErrorOf([&] { ws.ReadViewGray("c.png"); });
  EXPECT_NE(resized.find(JoinPaths(dir, "images", "c.png") + " is 32 x 24"), std::string::npos)
      << resized;
  EXPECT_NE(resized.find("is 64 x 48"), std::string::npos) << resized;
  EXPECT_NE(ErrorOf([&] { ws.ReadViewRgb("c.png"); }).find("is 32 x 24"), std::string::npos);
  EXPECT_EQ(ws.ImagePath("a.png"), JoinPaths(dir, "images", "a.png"));
  EXPECT_EQ(ws.DepthMapPath("a.png"),
            JoinPaths(dir, "stereo", "depth_maps", "a.png.geometric.bin"));
  EXPECT_EQ(ws.NormalMapPath("a.png", "photometric"),
            JoinPaths(dir, "stereo", "normal_maps", "a.png.photometric.bin"));
  EXPECT_THROW(ws.DepthMapPath("a.png", "geometrical"), Error);
  EXPECT_EQ(ws.MaskPath("a.png"), "");
  EXPECT_EQ(ws.MaskPath("b.png"), JoinPaths(dir, "masks", "b.png.png"));
  EXPECT_EQ(ws.ImagesWithoutMask(), (std::vector<std::string>{"a.png", "c.png"}));
  EXPECT_NE(ws.OrientationMapPath("a.png", 0), ws.OrientationMapPath("a.png", 1));

  // An explicit mask folder; 3.12+ naming (the name itself when it ends in .png).
  const std::string other_masks = JoinPaths(dir, "other_masks");
  std::filesystem::create_directories(other_masks);
  cv::imwrite(JoinPaths(other_masks, "a.png"), cv::Mat(48, 64, CV_8U, cv::Scalar(255)));
  const Workspace ws2 = Workspace::Read(dir, other_masks);
  EXPECT_EQ(ws2.MaskPath("a.png"), JoinPaths(other_masks, "a.png"));
  EXPECT_EQ(ws2.MaskPath("b.png"), "");
  EXPECT_EQ(ws2.ImagesWithoutMask(), (std::vector<std::string>{"b.png", "c.png"}));
  EXPECT_NE(ErrorOf([&] { Workspace::Read(dir, JoinPaths(dir, "nomasks")); }).find("nomasks"),
            std::string::npos);
  // Masks named for no image (the image's stem, the usual slip): an error with COLMAP's naming,
  // not a run without masks; so is a mask folder given that holds no image file (other files
  // do not count).
  const std::string stems = JoinPaths(dir, "stem_masks");
  std::filesystem::create_directories(stems);
  std::ofstream(JoinPaths(stems, "notes.txt")) << "drawn by hand";
  EXPECT_NE(ErrorOf([&] { Workspace::Read(dir, stems); }).find("it holds no image file"),
            std::string::npos);
  cv::imwrite(JoinPaths(stems, "a.jpg"), cv::Mat(48, 64, CV_8U, cv::Scalar(255)));
  const std::string stem_error = ErrorOf([&] { Workspace::Read(dir, stems); });
  EXPECT_NE(stem_error.find("No mask in " + stems + " belongs to an image"), std::string::npos)
      << stem_error;
  EXPECT_NE(stem_error.find("holds a.jpg"), std::string::npos) << stem_error;
  EXPECT_NE(stem_error.find(JoinPaths(stems, "a.png.png")), std::string::npos) << stem_error;
}

// A mask a few percent off its image's size (drawn on the photo before the undistorter) is
// warned about; one of the same size or a scaled copy (twice the size) is not, nor one of
// another aspect ratio (refused when read).
TEST(Workspace, MasksAFewPercentOffTheImageSizeAreWarnedAbout) {
  const std::string dir = MakeTestDir("ws_mask_sizes");
  WriteTestWorkspace(dir, MakePlaneModel());  // 64 x 48 images
  CreateDirs(JoinPaths(dir, "masks"));
  cv::imwrite(JoinPaths(dir, "masks", "a.png.png"), cv::Mat(48, 64, CV_8U, cv::Scalar(255)));
  cv::imwrite(JoinPaths(dir, "masks", "b.png.png"), cv::Mat(96, 128, CV_8U, cv::Scalar(255)));
  cv::imwrite(JoinPaths(dir, "masks", "c.png.png"), cv::Mat(48, 64, CV_8U, cv::Scalar(255)));
  ::testing::internal::CaptureStderr();
  Workspace::Read(dir);
  std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(log.find("a few percent off"), std::string::npos) << log;
  cv::imwrite(JoinPaths(dir, "masks", "c.png.png"), cv::Mat(49, 66, CV_8U, cv::Scalar(255)));
  ::testing::internal::CaptureStderr();
  Workspace::Read(dir);
  log = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("1 mask(s) a few percent off their image's size, c.png (66 x 49 for 64 x 48)"),
            std::string::npos)
      << log;
  // One of another aspect ratio is no scaled copy: refused when read, not said to be read as
  // one.
  cv::imwrite(JoinPaths(dir, "masks", "c.png.png"), cv::Mat(48, 60, CV_8U, cv::Scalar(255)));
  ::testing::internal::CaptureStderr();
  const Workspace ws = Workspace::Read(dir);
  log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(log.find("a few percent off"), std::string::npos) << log;
  EXPECT_NE(ErrorOf([&] { ReadMask(ws.MaskPath("c.png"), 64, 48); })
                .find("is 60 x 48, another aspect ratio"),
            std::string::npos);
}

TEST(Workspace, BadWorkspaces) {
  const std::string dir = MakeTestDir("ws_bad");
  // Missing folder, missing sparse model.
  EXPECT_NE(ErrorOf([&] { Workspace::Read(JoinPaths(dir, "none")); }).find("Missing workspace"),
            std::string::npos);
  CreateDirs(JoinPaths(dir, "empty_dir"));
  EXPECT_NE(ErrorOf([&] { Workspace::Read(JoinPaths(dir, "empty_dir")); })
                .find("Missing sparse model"),
            std::string::npos);
  // A file where a folder belongs is said to be one, not missing.
  const std::string file = JoinPaths(dir, "a_file");
  WriteFileAtomically(file, [](std::ostream& out) { out << "x"; });
  EXPECT_EQ(ErrorOf([&] { Workspace::Read(file); }),
            "The workspace folder " + file + " is a file, not a folder");
  WriteFileAtomically(JoinPaths(dir, "sparse_file", "sparse"),
                      [](std::ostream& out) { out << "x"; });
  EXPECT_EQ(ErrorOf([&] { Workspace::Read(JoinPaths(dir, "sparse_file")); }),
            "The sparse model folder " + JoinPaths(dir, "sparse_file", "sparse") +
                " is a file, not a folder");
  // Empty workspace: a model without images.
  Reconstruction empty;
  WriteReconstruction(empty, JoinPaths(dir, "empty", "sparse"), ModelFormat::kText);
  EXPECT_NE(ErrorOf([&] { Workspace::Read(JoinPaths(dir, "empty")); }).find("no images"),
            std::string::npos);
  // An image of the model that images/ lacks (`colmap image_undistorter --image_list_path`
  // writes the whole model, only the listed images): said, and no view; its image_idx is
  // still its record's place in the model (fused.ply.vis counts it).
  const std::string missing = JoinPaths(dir, "missing");
  WriteTestWorkspace(missing, MakePlaneModel());
  std::filesystem::remove(JoinPaths(missing, "images", "b.png"));
  ::testing::internal::CaptureStderr();
  const Workspace partial = Workspace::Read(missing);
  const std::string warning = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(warning.find("holds 2 of the 3 images of the model"), std::string::npos) << warning;
  EXPECT_NE(warning.find("(b.png)"), std::string::npos) << warning;
  EXPECT_EQ(partial.ImageNames(), (std::vector<std::string>{"a.png", "c.png"}));
  EXPECT_EQ(partial.SelectImages({}), partial.ImageNames());
  EXPECT_EQ(partial.ImageIdx("b.png"), 1);
  EXPECT_EQ(partial.ImageIdx("c.png"), 2);
  EXPECT_FALSE(partial.HasImageFile("b.png"));
  EXPECT_TRUE(partial.HasImageFile("c.png"));
  EXPECT_FALSE(partial.HasImageFile("d.png"));
  const std::string error = ErrorOf([&] { partial.SelectImages({"b.png"}); });
  EXPECT_NE(error.find("Image `b.png` (--image_names) is in the model of " + missing +
                       " but not in its images folder: " + JoinPaths(missing, "images", "b.png")),
            std::string::npos)
      << error;
  // None of them there: an error naming the first.
  for (const char* name : {"a.png", "c.png"}) {
    std::filesystem::remove(JoinPaths(missing, "images", name));
  }
  const std::string none = ErrorOf([&] { Workspace::Read(missing); });
  EXPECT_NE(none.find("None of the 3 images of the model"), std::string::npos) << none;
  EXPECT_NE(none.find(JoinPaths(missing, "images", "a.png")), std::string::npos) << none;
  // A file where the masks folder belongs: an error, not a workspace without masks.
  const std::string masks_file = JoinPaths(dir, "masks_file");
  WriteTestWorkspace(masks_file, MakePlaneModel());
  WriteFileAtomically(JoinPaths(masks_file, "masks"), [](std::ostream& out) { out << "x"; });
  EXPECT_EQ(ErrorOf([&] { Workspace::Read(masks_file); }),
            "The mask folder " + JoinPaths(masks_file, "masks") + " is a file, not a folder");
  // Names that leave images/ or name a file two ways: every output of a view is named after
  // it, so they would be written outside the workspace or over each other's. Sub-folders are
  // fine.
  for (const char* bad : {"../a.png", "./a.png", "sub//a.png", "/tmp/a.png", "sub/../a.png"}) {
    const std::string bad_dir = JoinPaths(dir, "bad_name");
    std::filesystem::remove_all(bad_dir);
    Reconstruction named = MakePlaneModel();
    named.images.at(1).name = bad;
    WriteReconstruction(named, JoinPaths(bad_dir, "sparse"), ModelFormat::kText);
    CreateDirs(JoinPaths(bad_dir, "images"));
    const std::string bad_error = ErrorOf([&] { Workspace::Read(bad_dir); });
    EXPECT_NE(bad_error.find(JoinPaths(bad_dir, "sparse") + ": image 1 is named '" + bad +
                             "', which is no path inside " + JoinPaths(bad_dir, "images")),
              std::string::npos)
        << bad_error;
  }
  // A distorted camera: reading works, CameraOf tells the user to undistort.
  const std::string distorted = JoinPaths(dir, "distorted");
  Reconstruction model = MakePlaneModel();
  model.cameras.at(1).model_id = 2;  // SIMPLE_RADIAL: f, cx, cy, k
  model.cameras.at(1).params = {50, 32, 24, 0.01};
  WriteTestWorkspace(distorted, model, true);
  const Workspace ws = Workspace::Read(distorted);
  EXPECT_NE(ErrorOf([&] { ws.CameraOf("a.png"); }).find("image_undistorter"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { ws.RequireUndistortedCameras(); }).find("SIMPLE_RADIAL"),
            std::string::npos);
}

// The message for a distorted camera names the image, the model folder it is described in, the
// camera and its model: the one message CalibrationMatrix gives too, with the location.
TEST(Workspace, DistortedCameraNamesTheModelFolder) {
  const std::string dir = MakeTestDir("ws_distorted");
  Reconstruction model = MakePlaneModel();
  model.cameras.at(2).model_id = 4;  // OPENCV: fx, fy, cx, cy, k1, k2, p1, p2
  model.cameras.at(2).params = {50, 50, 32, 24, 0.01, 0, 0, 0};
  WriteTestWorkspace(dir, model);
  const Workspace ws = Workspace::Read(dir);
  const std::string message = ErrorOf([&] { ws.RequireUndistortedCameras(); });
  EXPECT_NE(message.find("Image b.png in " + JoinPaths(dir, "sparse") +
                         ": camera 2 has model OPENCV with distortion; the dense stage needs "
                         "undistorted PINHOLE or SIMPLE_PINHOLE cameras (or SIMPLE_RADIAL, "
                         "RADIAL, OPENCV or FULL_OPENCV with every distortion parameter 0): run "
                         "`colmap image_undistorter"),
            std::string::npos)
      << message;
  const std::string bare = ErrorOf([&] { model.cameras.at(2).CalibrationMatrix(); });
  EXPECT_NE(bare.find("Camera 2 has model OPENCV with distortion; the dense stage needs"),
            std::string::npos)
      << bare;
}

TEST(Images, GrayRgbAndSixteenBit) {
  const std::string dir = MakeTestDir("images");
  cv::Mat bgr(2, 3, CV_8UC3, cv::Scalar(0, 0, 0));
  bgr.at<cv::Vec3b>(0, 1) = cv::Vec3b(0, 0, 255);    // red
  bgr.at<cv::Vec3b>(1, 2) = cv::Vec3b(255, 0, 0);    // blue
  const std::string path = JoinPaths(dir, "c.png");
  ASSERT_TRUE(cv::imwrite(path, bgr));
  const FloatMap rgb = ReadImageRgb(path);
  ASSERT_EQ(rgb.Channels(), 3);
  EXPECT_FLOAT_EQ(rgb.At(0, 1, 0), 1.0f);
  EXPECT_FLOAT_EQ(rgb.At(0, 1, 2), 0.0f);
  EXPECT_FLOAT_EQ(rgb.At(1, 2, 2), 1.0f);
  const FloatMap gray = ReadImageGray(path);
  ASSERT_EQ(gray.Channels(), 1);
  EXPECT_NEAR(gray.At(0, 1), 0.299f, 1e-6);
  EXPECT_NEAR(gray.At(1, 2), 0.114f, 1e-6);
  EXPECT_EQ(gray.At(0, 0), 0.0f);

  cv::Mat sixteen(2, 2, CV_16U, cv::Scalar(65535));
  sixteen.at<uint16_t>(1, 0) = 32768;
  const std::string path16 = JoinPaths(dir, "g16.png");
  ASSERT_TRUE(cv::imwrite(path16, sixteen));
  const FloatMap g16 = ReadImageGray(path16);
  EXPECT_FLOAT_EQ(g16.At(0, 0), 1.0f);
  EXPECT_NEAR(g16.At(1, 0), 32768.0 / 65535.0, 1e-6);

  // Float TIFFs: read as they are in [0, 1]; one holding 0-255 is refused, not read 255 times
  // too bright.
  cv::Mat unit(2, 2, CV_32F, cv::Scalar(0.25));
  const std::string unit_path = JoinPaths(dir, "unit.tif");
  ASSERT_TRUE(cv::imwrite(unit_path, unit));
  EXPECT_FLOAT_EQ(ReadImageGray(unit_path).At(1, 1), 0.25f);
  cv::Mat bytes_as_float(2, 2, CV_32F, cv::Scalar(200));
  const std::string bytes_path = JoinPaths(dir, "bytes.tif");
  ASSERT_TRUE(cv::imwrite(bytes_path, bytes_as_float));
  EXPECT_NE(ErrorOf([&] { ReadImageGray(bytes_path); })
                .find("bytes.tif holds values from 200 to 200, not in [0, 1]"),
            std::string::npos);

  // WriteImage / ReadImageRgb round trip within 8-bit quantisation.
  FloatMap picture(5, 4, 3);
  for (size_t i = 0; i < picture.Data().size(); ++i) picture.Data()[i] = (i % 11) / 10.0f;
  WriteImage(JoinPaths(dir, "w.png"), picture);
  const FloatMap back = ReadImageRgb(JoinPaths(dir, "w.png"));
  for (size_t i = 0; i < picture.Data().size(); ++i) {
    EXPECT_NEAR(back.Data()[i], picture.Data()[i], 0.5 / 255 + 1e-6);
  }
  // The OpenCV overload: B, G, R bytes as imwrite takes them; a format OpenCV cannot write
  // is named and leaves nothing behind.
  cv::Mat bytes(2, 3, CV_8UC3, cv::Scalar(10, 20, 30));
  WriteImage(JoinPaths(dir, "bgr.png"), bytes);
  const FloatMap read = ReadImageRgb(JoinPaths(dir, "bgr.png"));
  EXPECT_NEAR(read.At(1, 2, 0), 30 / 255.0, 1e-6);
  EXPECT_NEAR(read.At(1, 2, 2), 10 / 255.0, 1e-6);
  EXPECT_NE(ErrorOf([&] { WriteImage(JoinPaths(dir, "bgr.nosuchformat"), bytes); })
                .find("bgr.nosuchformat"),
            std::string::npos);
  EXPECT_FALSE(ExistsFile(JoinPaths(dir, "bgr.nosuchformat")));
  EXPECT_NE(ErrorOf([&] { ReadImageGray(JoinPaths(dir, "none.png")); }).find("none.png"),
            std::string::npos);
  WriteFileAtomically(JoinPaths(dir, "junk.png"), [](std::ostream& out) { out << "junk"; });
  EXPECT_NE(ErrorOf([&] { ReadImageGray(JoinPaths(dir, "junk.png")); }).find("junk.png"),
            std::string::npos);
}

// A truncated file is an error naming it: libpng fails, and libjpeg would decode the part
// that is there (the rest grey) but for the check of the end-of-image marker. Bytes a camera
// appends after the image are allowed, whatever markers they hold. Progressive JPEGs (several
// scans) and restart markers within a scan are walked through.
TEST(Images, TruncatedImagesAreErrors) {
  const std::string dir = MakeTestDir("truncated");
  cv::Mat noise(48, 64, CV_8UC3);
  cv::randu(noise, cv::Scalar::all(0), cv::Scalar::all(255));
  for (const std::string extension : {".jpg", ".png"}) {
    const std::string whole = JoinPaths(dir, "whole" + extension);
    ASSERT_TRUE(cv::imwrite(whole, noise));
    EXPECT_EQ(ReadImageRgb(whole).Width(), 64);
    const std::string bytes = ReadTextFile(whole);
    const std::string cut = JoinPaths(dir, "cut" + extension);
    WriteFileAtomically(cut, [&](std::ostream& out) { out << bytes.substr(0, bytes.size() / 2); });
    const std::string error = ErrorOf([&] { ReadImageGray(cut); });
    EXPECT_NE(error.find(cut), std::string::npos) << error;
    EXPECT_NE(error.find(extension == ".jpg" ? "Truncated image" : "truncated"),
              std::string::npos)
        << error;
    EXPECT_NE(error.find(std::to_string(bytes.size() / 2) + " bytes"), std::string::npos)
        << error;
  }
  const std::string trailer = JoinPaths(dir, "trailer.jpg");
  // A motion photo's video after the image: a start-of-scan marker (FF DA) and no end marker.
  WriteFileAtomically(trailer, [&](std::ostream& out) {
    out << ReadTextFile(JoinPaths(dir, "whole.jpg")) << "ftypmp42"
        << std::string("\x00\x00\xff\xda\x12\x34", 6) << "appended by a camera";
  });
  EXPECT_EQ(ReadImageGray(trailer).Height(), 48);
  // Several scans: read whole (libjpeg refuses a cut progressive file itself).
  const std::string progressive = JoinPaths(dir, "progressive.jpg");
  ASSERT_TRUE(cv::imwrite(progressive, noise, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}));
  EXPECT_EQ(ReadImageGray(progressive).Width(), 64);
  // Restart markers within the scan: read whole, and refused when cut within the scan or just
  // before the end-of-image marker.
  const std::string restarts = JoinPaths(dir, "restarts.jpg");
  ASSERT_TRUE(cv::imwrite(restarts, noise, {cv::IMWRITE_JPEG_RST_INTERVAL, 1}));
  EXPECT_EQ(ReadImageGray(restarts).Width(), 64);
  const std::string restart_bytes = ReadTextFile(restarts);
  for (const size_t kept : {restart_bytes.size() / 2, restart_bytes.size() - 2}) {
    const std::string cut = JoinPaths(dir, "restarts_cut.jpg");
    WriteFileAtomically(cut, [&](std::ostream& out) { out << restart_bytes.substr(0, kept); });
    const std::string error = ErrorOf([&] { ReadImageGray(cut); });
    EXPECT_NE(error.find("Truncated image"), std::string::npos)
        << kept << " of " << restart_bytes.size() << " bytes: " << error;
  }
  const std::string empty = JoinPaths(dir, "empty.png");
  WriteFileAtomically(empty, [](std::ostream&) {});
  EXPECT_NE(ErrorOf([&] { ReadMask(empty, 4, 4); }).find("Cannot decode mask"), std::string::npos);
}

// `png`'s bytes with the IHDR chunk's width and height replaced and its CRC recomputed, so that
// a decoder takes the header as valid (the pixel data still describes the old size).
std::string PngStating(const std::string& png, uint32_t width, uint32_t height) {
  std::string bytes = png;
  const auto put = [&bytes](size_t at, uint32_t value) {
    for (int k = 0; k < 4; ++k) bytes[at + k] = static_cast<char>(value >> (24 - 8 * k));
  };
  put(16, width);
  put(20, height);
  uint32_t crc = 0xFFFFFFFFu;  // CRC-32 of the chunk type and data (bytes 12-28), PNG's
  for (size_t i = 12; i < 29; ++i) {
    crc ^= static_cast<uint8_t>(bytes[i]);
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  put(29, crc ^ 0xFFFFFFFFu);
  return bytes;
}

// An image or mask whose PNG header states another size than its camera's (or another aspect
// ratio) is refused from the header, naming the file, without decoding it (a 40000 x 40000 PNG
// of zeros is a few hundred kilobytes but gigabytes decoded); one OpenCV will not decode at all
// is an error naming the file, not OpenCV's bare assertion.
TEST(Images, HugeStatedSizesAreRefusedNamingTheFile) {
  const std::string dir = MakeTestDir("ws_huge_png");
  WriteTestWorkspace(dir, MakePlaneModel());  // 64 x 48 images
  const std::string image = JoinPaths(dir, "images", "a.png");
  const std::string png = ReadTextFile(image);
  WriteFileAtomically(image, [&](std::ostream& out) { out << PngStating(png, 40000, 40000); });
  const Workspace ws = Workspace::Read(dir);
  std::string error = ErrorOf([&] { ws.ReadViewGray("a.png"); });
  EXPECT_NE(error.find("Image " + image + " is 40000 x 40000 but its camera 1 is 64 x 48"),
            std::string::npos)
      << error;
  error = ErrorOf([&] { ReadImageGray(image); });
  EXPECT_NE(error.find("Cannot decode image " + image), std::string::npos) << error;
  EXPECT_NE(error.find("OpenCV refused it"), std::string::npos) << error;
  const std::string mask = JoinPaths(dir, "mask.png");
  WriteFileAtomically(mask, [&](std::ostream& out) { out << PngStating(png, 40000, 20000); });
  error = ErrorOf([&] { ReadMask(mask, 64, 48); });
  EXPECT_NE(error.find("Mask " + mask + " is 40000 x 20000, another aspect ratio"),
            std::string::npos)
      << error;
}

TEST(Images, MaskResizedNearestAndAllZeroOrAnotherAspectIsAnError) {
  const std::string dir = MakeTestDir("masks");
  cv::Mat mask(2, 2, CV_8U, cv::Scalar(0));
  mask.at<uint8_t>(0, 1) = 255;
  const std::string path = JoinPaths(dir, "m.png");
  ASSERT_TRUE(cv::imwrite(path, mask));
  const FloatMap m = ReadMask(path, 4, 4);
  EXPECT_EQ(m.At(0, 3), 1.0f);
  EXPECT_EQ(m.At(1, 2), 1.0f);
  EXPECT_EQ(m.At(0, 0), 0.0f);
  EXPECT_EQ(m.At(3, 3), 0.0f);
  const FloatMap ones = ReadMask("", 3, 2);
  EXPECT_EQ(ones.Data(), std::vector<float>(6, 1.0f));
  const std::string zero = JoinPaths(dir, "zero.png");
  ASSERT_TRUE(cv::imwrite(zero, cv::Mat(3, 3, CV_8U, cv::Scalar(0))));
  EXPECT_NE(ErrorOf([&] { ReadMask(zero, 3, 3); }).find("zero.png excludes every pixel"),
            std::string::npos);
  // A mask whose one kept pixel falls between the samples of a smaller size (max_image_size)
  // says so, rather than that it excludes every pixel.
  cv::Mat one(4, 4, CV_8U, cv::Scalar(0));
  one.at<uint8_t>(1, 1) = 255;
  const std::string one_path = JoinPaths(dir, "one.png");
  ASSERT_TRUE(cv::imwrite(one_path, one));
  const std::string scaled = ErrorOf([&] { ReadMask(one_path, 2, 2); });
  EXPECT_NE(scaled.find("one.png keeps 1 pixel(s) at its own size but none once scaled to 2x2"),
            std::string::npos)
      << scaled;
  // Scaled copies are read, with a pixel of rounding (960 x 640 at 160 px wide is 106.7 rows);
  // another aspect ratio is named with both sizes.
  const std::string wide = JoinPaths(dir, "wide.png");
  ASSERT_TRUE(cv::imwrite(wide, cv::Mat(640, 960, CV_8U, cv::Scalar(255))));
  EXPECT_EQ(ReadMask(wide, 160, 107).Width(), 160);
  EXPECT_EQ(ReadMask(wide, 160, 106).Height(), 106);
  const std::string error = ErrorOf([&] { ReadMask(wide, 600, 450); });
  EXPECT_NE(error.find("wide.png is 960 x 640"), std::string::npos) << error;
  EXPECT_NE(error.find("600 x 450"), std::string::npos) << error;
  EXPECT_NE(ErrorOf([&] { ReadMask(wide, 160, 110); }).find("aspect ratio"), std::string::npos);
  // Width and height swapped (an editor that applied an EXIF orientation): said so.
  EXPECT_NE(ErrorOf([&] { ReadMask(wide, 640, 960); }).find("its width and height swapped"),
            std::string::npos);
  EXPECT_EQ(ErrorOf([&] { ReadMask(wide, 600, 450); }).find("swapped"), std::string::npos);

  // Alpha: a white-on-transparent mask (colour and alpha agree) and a black and white one with
  // an opaque alpha (as editors write) are read by their colour; a cut-out (the photo in colour,
  // the mask in alpha) is refused, where COLMAP would keep every pixel.
  for (const double background_alpha : {0.0, 255.0}) {
    cv::Mat agree(8, 8, CV_8UC4, cv::Scalar(0, 0, 0, background_alpha));
    agree(cv::Rect(0, 0, 4, 8)).setTo(cv::Scalar(255, 255, 255, 255));
    const std::string agree_path = JoinPaths(dir, "agree.png");
    ASSERT_TRUE(cv::imwrite(agree_path, agree));
    const FloatMap agreed = ReadMask(agree_path, 8, 8);
    EXPECT_EQ(agreed.At(0, 0), 1.0f) << background_alpha;
    EXPECT_EQ(agreed.At(0, 7), 0.0f) << background_alpha;
  }
  cv::Mat cut_out(8, 8, CV_8UC4, cv::Scalar(90, 120, 200, 0));
  cut_out(cv::Rect(0, 0, 4, 8)).setTo(cv::Scalar(90, 120, 200, 255));
  const std::string cut_out_path = JoinPaths(dir, "cut_out.png");
  ASSERT_TRUE(cv::imwrite(cut_out_path, cut_out));
  const std::string alpha_error = ErrorOf([&] { ReadMask(cut_out_path, 8, 8); });
  EXPECT_NE(alpha_error.find("cut_out.png: 50% of its pixels are transparent in its alpha "
                             "channel but kept by their colour"),
            std::string::npos)
      << alpha_error;
}

}  // namespace
}  // namespace hairmvs
