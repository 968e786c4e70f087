#include "src/evaluation/ground_truth.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <random>

#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/npz.h"
#include "src/core/test_util.h"
#include "src/evaluation/evaluation_util.h"

namespace hairmvs {
namespace {

using testing_util::MakeTestDir;

// Curved strands with points ~6 mm apart, like the shared sets.
GroundTruthStrands TestStrands() {
  GroundTruthStrands strands;
  strands.offsets.push_back(0);
  for (int s = 0; s < 6; ++s) {
    const int n = (s == 5) ? 1 : 8 + s;  // the last strand is a single point
    for (int k = 0; k < n; ++k) {
      const double a = 0.15 * k + s;
      strands.points.emplace_back(0.01f * s + 0.02f * std::cos(a), 0.02f * std::sin(a),
                                  0.006f * k);
    }
    strands.offsets.push_back(strands.points.size());
  }
  return strands;
}

// Brute force: the minimum over a very fine sampling of every spline segment.
double BruteForceDistance(const GroundTruthStrands& strands, const Eigen::Vector3d& x) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t s = 0; s < strands.NumStrands(); ++s) {
    const int64_t b = strands.offsets[s], n = strands.offsets[s + 1] - b;
    auto p = [&](int64_t k) {
      return strands.points[b + std::clamp<int64_t>(k, 0, n - 1)].cast<double>();
    };
    if (n == 1) best = std::min(best, (p(0) - x).norm());
    for (int64_t k = 0; k + 1 < n; ++k) {
      for (int j = 0; j <= 20000; ++j) {
        const Eigen::Vector3d c = CatmullRom(p(k - 1), p(k), p(k + 1), p(k + 2), j / 20000.0);
        best = std::min(best, (c - x).norm());
      }
    }
  }
  return best;
}

TEST(GroundTruth, CatmullRomInterpolates) {
  const Eigen::Vector3d p0(0, 0, 0), p1(1, 0, 0), p2(2, 1, 0), p3(3, 3, 1);
  EXPECT_TRUE(CatmullRom(p0, p1, p2, p3, 0.0).isApprox(p1));
  EXPECT_TRUE(CatmullRom(p0, p1, p2, p3, 1.0).isApprox(p2));
  // On collinear equally spaced points the uniform spline is the line itself.
  const Eigen::Vector3d mid = CatmullRom(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1),
                                         Eigen::Vector3d(2, 2, 2), Eigen::Vector3d(3, 3, 3), 0.5);
  EXPECT_TRUE(mid.isApprox(Eigen::Vector3d(1.5, 1.5, 1.5)));
}

TEST(GroundTruth, StrandDistanceMatchesBruteForce) {
  const GroundTruthStrands strands = TestStrands();
  const StrandDistance distance(strands, 2e-4);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.03, 0.09);
  std::uniform_real_distribution<double> noise(-1e-3, 1e-3);
  std::vector<Eigen::Vector3d> queries;
  for (int i = 0; i < 20; ++i) queries.emplace_back(u(rng), u(rng) * 0.5, u(rng) * 0.6);
  // Points close to the strands, where the spline-vs-polyline difference matters.
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3f& p = strands.points[i % strands.points.size()];
    queries.push_back(p.cast<double>() + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  }
  const std::vector<double> batch = distance.Distances(queries);
  for (size_t i = 0; i < queries.size(); ++i) {
    const double expected = BruteForceDistance(strands, queries[i]);
    EXPECT_NEAR(distance.Distance(queries[i]), expected, 1e-6) << i;
    EXPECT_EQ(batch[i], distance.Distance(queries[i]));
  }
  // Sample spacing respected: at least length / spacing samples.
  EXPECT_GT(distance.NumSamples(), 5u * 0.006 / 2e-4);
  // A stored point is on its strand.
  EXPECT_NEAR(distance.Distance(strands.points[3].cast<double>()), 0.0, 1e-7);
}

// A spacing far below the strands' scale is refused from the count of the samples it would
// take, before they are made.
TEST(GroundTruth, StrandDistanceTooFineForMemoryIsAnError) {
  const std::string error =
      testing_util::ErrorOf([&] { StrandDistance(TestStrands(), 1e-12); });
  EXPECT_NE(error.find("Sampling the true strands every 1e-12 m would take"), std::string::npos)
      << error;
}

TEST(GroundTruth, MissingFolderIsNamedAsTheGroundTruth) {
  const std::string missing = JoinPaths(::testing::TempDir(), "hairmvs_gt_no_such_folder");
  std::filesystem::remove_all(missing);
  const std::vector<std::function<void()>> readers = {
      [&] { ReadGroundTruthView(missing, "v0.png"); },
      [&] { ReadGroundTruthCameras(missing); },
      [&] { ReadGroundTruthStrands(missing); },
      [&] { ReadTrueCameras(missing, true); }};  // the evaluators' own check of cameras.npz
  for (const auto& read : readers) {
    const std::string message = testing_util::ErrorOf(read);
    EXPECT_NE(message.find("ground truth folder"), std::string::npos) << message;
    EXPECT_NE(message.find(missing), std::string::npos) << message;
  }
}

TEST(GroundTruth, FilesRoundTrip) {
  const std::string dir = MakeTestDir("files");
  GroundTruthView view;
  view.depth = FloatMap(5, 4, 1, 0.0f);
  view.label.assign(20, kLabelBackground);
  view.depth.At(1, 2) = 0.61f;
  view.label[1 * 5 + 2] = kLabelHair;
  WriteGroundTruthView(dir, "v0.png", view);
  EXPECT_TRUE(ExistsFile(JoinPaths(dir, "v0.npz")));
  const GroundTruthView back = ReadGroundTruthView(dir, "v0.png");
  EXPECT_EQ(back.depth.Width(), 5);
  EXPECT_EQ(back.depth.Height(), 4);
  EXPECT_EQ(back.depth.At(1, 2), 0.61f);
  EXPECT_EQ(back.label, view.label);
  EXPECT_THROW(ReadGroundTruthView(dir, "v1.png"), Error);

  GroundTruthCameras cameras;
  cameras.names = {"v0.png", "v1.png"};
  cameras.R = {Eigen::Matrix3d::Identity(),
               Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix()};
  cameras.t = {Eigen::Vector3d(0, 0, 0.6), Eigen::Vector3d(0.1, 0, 0.6)};
  cameras.K << 100, 0, 2.5, 0, 100, 2, 0, 0, 1;
  cameras.width = 5;
  cameras.height = 4;
  WriteGroundTruthCameras(dir, cameras);
  const GroundTruthCameras cameras_back = ReadGroundTruthCameras(dir);
  EXPECT_EQ(cameras_back.names, cameras.names);
  EXPECT_TRUE(cameras_back.R[1].isApprox(cameras.R[1]));
  EXPECT_TRUE(cameras_back.t[1].isApprox(cameras.t[1]));
  EXPECT_TRUE(cameras_back.K.isApprox(cameras.K));
  EXPECT_EQ(cameras_back.width, 5);
  EXPECT_EQ(cameras_back.Find("v1.png"), 1);
  EXPECT_EQ(cameras_back.Find("v9.png"), -1);

  const GroundTruthStrands strands = TestStrands();
  WriteGroundTruthStrands(dir, strands);
  const GroundTruthStrands strands_back = ReadGroundTruthStrands(dir);
  EXPECT_EQ(strands_back.offsets, strands.offsets);
  ASSERT_EQ(strands_back.points.size(), strands.points.size());
  EXPECT_EQ(strands_back.points[7], strands.points[7]);
  // A point that is not finite is named with its file.
  GroundTruthStrands stray = strands;
  stray.points[7].y() = std::numeric_limits<float>::quiet_NaN();
  WriteGroundTruthStrands(dir, stray);
  const std::string error = testing_util::ErrorOf([&] { ReadGroundTruthStrands(dir); });
  EXPECT_NE(error.find("strands_points.npy: point 7 is not finite"), std::string::npos) << error;
}

// Ground truth that cannot be true (a nan or negative depth, a label that is not 0-2 or is
// stored as a float, cameras with nan, sizes that are no pixel counts, a matrix that is no
// rotation) is refused naming the file and the array: it would otherwise score as silently
// wrong figures (a null mean error, completeness 0, every pixel hair).
TEST(GroundTruth, ValuesThatCannotBeTrueAreRefusedNamingTheFile) {
  const std::string dir = MakeTestDir("bad_values");
  const std::string view_path = JoinPaths(dir, "v0.npz");
  const auto view_error = [&](const std::function<void(GroundTruthView*)>& edit) {
    GroundTruthView view;
    view.depth = FloatMap(5, 4, 1, 0.6f);
    view.label.assign(20, kLabelHair);
    edit(&view);
    WriteGroundTruthView(dir, "v0.png", view);
    return testing_util::ErrorOf([&] { ReadGroundTruthView(dir, "v0.png"); });
  };
  EXPECT_EQ(view_error([](GroundTruthView*) {}), "(no error)");
  const std::vector<std::pair<std::function<void(GroundTruthView*)>, std::string>> view_cases = {
      {[](GroundTruthView* v) { v->depth.Data()[7] = std::nanf(""); },
       view_path + ": depth: element 7 is nan; every element must be finite and >= 0"},
      {[](GroundTruthView* v) { v->depth.Data()[3] = -0.5f; }, ": depth: element 3 is -0.5"},
      {[](GroundTruthView* v) { v->label[7] = 3; },
       view_path + ": label of pixel (2, 1) is 3; labels are 0 (background), 1 (head skin) or "
                   "2 (hair)"}};
  for (const auto& [edit, expected] : view_cases) {
    const std::string error = view_error(edit);
    EXPECT_NE(error.find(expected), std::string::npos) << error;
  }
  std::map<std::string, NpyArray> arrays;
  arrays["depth"] = NpyArray::FromVector(std::vector<float>(20, 0.6f), {4, 5});
  arrays["label"] = NpyArray::FromVector(std::vector<float>(20, 2.5f), {4, 5});
  WriteNpz(view_path, arrays);
  std::string error = testing_util::ErrorOf([&] { ReadGroundTruthView(dir, "v0.png"); });
  EXPECT_NE(error.find(view_path + ": label must be an integer array"), std::string::npos)
      << error;

  GroundTruthCameras cameras;
  cameras.names = {"v0.png", "v1.png"};
  cameras.R = {Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Identity()};
  cameras.t = {Eigen::Vector3d(0, 0, 0.6), Eigen::Vector3d(0.1, 0, 0.6)};
  cameras.K << 100, 0, 2.5, 0, 100, 2, 0, 0, 1;
  cameras.width = 5;
  cameras.height = 4;
  const std::string cameras_path = JoinPaths(dir, "cameras.npz");
  const auto cameras_error = [&](const std::function<void(GroundTruthCameras*)>& edit) {
    GroundTruthCameras edited = cameras;
    edit(&edited);
    WriteGroundTruthCameras(dir, edited);
    return testing_util::ErrorOf([&] { ReadGroundTruthCameras(dir); });
  };
  EXPECT_EQ(cameras_error([](GroundTruthCameras*) {}), "(no error)");
  const std::vector<std::pair<std::function<void(GroundTruthCameras*)>, std::string>>
      camera_cases = {
          {[](GroundTruthCameras* c) { c->K(0, 0) = std::nan(""); },
           cameras_path + ": K: element 0 is nan; every element must be finite"},
          {[](GroundTruthCameras* c) { c->K(1, 1) = -100; }, ": K's focal lengths (100, -100)"},
          {[](GroundTruthCameras* c) { c->t[1].y() = INFINITY; }, ": t: element 4 is inf"},
          {[](GroundTruthCameras* c) { c->R[1](0, 1) = 0.1; },
           cameras_path + ": R[1] (v1.png) is no rotation (not orthonormal)"},
          {[](GroundTruthCameras* c) { c->R[0] = -Eigen::Matrix3d::Identity(); },
           ": R[0] (v0.png) is no rotation (a reflection)"},
          {[](GroundTruthCameras* c) { c->hair_centre.y() = std::nan(""); },
           cameras_path + ": hair_centre: element 1 is nan"},
          {[](GroundTruthCameras* c) { c->width = 0; },
           cameras_path + ": width: 0 is not a whole number of pixels in 1..1000000"}};
  for (const auto& [edit, expected] : camera_cases) {
    error = cameras_error(edit);
    EXPECT_NE(error.find(expected), std::string::npos) << error;
  }
  // Arrays of the wrong kind: names as numbers, a size too large for an int or fractional.
  WriteGroundTruthCameras(dir, cameras);
  std::map<std::string, NpyArray> camera_arrays = ReadNpz(cameras_path);
  camera_arrays["names"] = NpyArray::FromVector(std::vector<double>{1, 2});
  camera_arrays["height"] = NpyArray::Scalar<double>(1e20);
  WriteNpz(cameras_path, camera_arrays);
  error = testing_util::ErrorOf([&] { ReadGroundTruthCameras(dir); });
  EXPECT_NE(error.find(cameras_path + ": names: expected a string (<U) array, found dtype <f8"),
            std::string::npos)
      << error;
  camera_arrays["names"] = NpyArray::FromStrings(cameras.names);
  WriteNpz(cameras_path, camera_arrays);
  error = testing_util::ErrorOf([&] { ReadGroundTruthCameras(dir); });
  EXPECT_NE(error.find(cameras_path + ": height: 1e+20 is not a whole number of pixels"),
            std::string::npos)
      << error;
  camera_arrays["height"] = NpyArray::Scalar<double>(4.5);
  WriteNpz(cameras_path, camera_arrays);
  error = testing_util::ErrorOf([&] { ReadGroundTruthCameras(dir); });
  EXPECT_NE(error.find(": height: 4.5 is not a whole number"), std::string::npos) << error;
}

}  // namespace
}  // namespace hairmvs
