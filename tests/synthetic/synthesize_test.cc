#include "hairmvs/synthesize.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>

#include "colmap_ext/workspace.h"
#include "src/core/file_util.h"
#include "src/core/npz.h"
#include "src/core/test_util.h"
#include "src/evaluation/ground_truth.h"

namespace hairmvs {
namespace {

namespace fs = std::filesystem;

using testing_util::MakeTestDir;

SynthesizeOptions SmallOptions(const std::string& path) {
  SynthesizeOptions options;
  options.output_path = path;
  options.width = 160;
  options.num_strands = 1500;
  options.sparse_samples_per_view = 150;
  options.seed = 5;
  return options;
}

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::vector<std::string> ListFiles(const std::string& root) {
  std::vector<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file()) files.push_back(fs::relative(e.path(), root).string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST(Synthesize, OptionsAreChecked) {
  SynthesizeOptions options;
  std::string error;
  EXPECT_FALSE(options.Check(&error));  // no output_path
  EXPECT_NE(error.find("output_path"), std::string::npos);
  options.output_path = "/tmp/x";
  options.num_groups = 9;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_THROW(RunSynthesize(options), Error);
  options.num_groups = 1;
  options.seed = -1;  // taken as unsigned, it was quietly 2^64 - 1
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("seed must be >= 0"), std::string::npos) << error;
  HairStyle style;
  EXPECT_TRUE(FromString("curly", &style));
  EXPECT_EQ(style, HairStyle::kCurly);
  EXPECT_FALSE(FromString("wavy", &style));
}

TEST(Synthesize, GantryWorkspaceReadsBackWithGroundTruth) {
  const std::string path = MakeTestDir("gantry");
  const SynthesizeResult result = RunSynthesize(SmallOptions(path));
  EXPECT_EQ(result.num_views, 4);
  EXPECT_EQ(result.width, 160);
  EXPECT_EQ(result.height, 107);

  const Workspace ws = Workspace::Read(JoinPaths(path, "dense"));
  ASSERT_EQ(ws.ImageNames().size(), 4u);
  EXPECT_EQ(ws.ImageNames()[0], "g0_c.png");
  const std::set<std::string> names(ws.ImageNames().begin(), ws.ImageNames().end());
  EXPECT_EQ(names, (std::set<std::string>{"g0_c.png", "g0_l.png", "g0_r.png", "g0_b.png"}));
  const Camera& camera = ws.CameraOf("g0_c.png");
  EXPECT_EQ(camera.ModelName(), "PINHOLE");
  EXPECT_EQ(camera.width, 160u);
  EXPECT_EQ(ws.MaskPath("g0_c.png"), JoinPaths(path, "dense", "masks", "g0_c.png.png"));
  EXPECT_TRUE(ExistsDir(JoinPaths(path, "dense", "stereo", "depth_maps")));
  EXPECT_TRUE(ExistsDir(JoinPaths(path, "dense", "stereo", "normal_maps")));
  EXPECT_EQ(ReadTextFile(JoinPaths(path, "dense", "stereo", "patch-match.cfg")),
            "g0_c.png\n__auto__, 20\ng0_l.png\n__auto__, 20\ng0_r.png\n__auto__, 20\n"
            "g0_b.png\n__auto__, 20\n");
  EXPECT_EQ(ReadTextFile(JoinPaths(path, "dense", "stereo", "fusion.cfg")),
            "g0_c.png\ng0_l.png\ng0_r.png\ng0_b.png\n");

  // Sparse points: seen in >= 2 views, tracks and points2D agree, the observations are the
  // projections of the points, and the true depth there matches.
  const Reconstruction& model = ws.Model();
  ASSERT_GT(model.points3D.size(), 50u);
  const std::string gt_path = JoinPaths(path, "gt");
  std::map<std::string, FloatMap> true_depths;  // per image name, read once
  for (const auto& [id, point] : model.points3D) {
    ASSERT_GE(point.track.size(), 2u);
    for (const TrackElement& el : point.track) {
      const Image& image = model.images.at(el.image_id);
      const Point2D& p2d = image.points2D.at(el.point2D_idx);
      EXPECT_EQ(p2d.point3D_id, id);
      const Eigen::Vector3d xc = image.R() * point.xyz + image.t();
      const Eigen::Vector3d uv = camera.CalibrationMatrix() * xc;
      // Exact projections (pixel centres at +0.5), up to the float depth a point was made from.
      EXPECT_LT((uv.head<2>() / uv.z() - p2d.xy).norm(), 1e-3);
      // The true depth of the pixel seen there: the point's own, within 2 px's footprint.
      auto truth = true_depths.find(image.name);
      if (truth == true_depths.end()) {
        truth = true_depths.emplace(image.name, ReadGroundTruthView(gt_path, image.name).depth)
                    .first;
      }
      const float depth = truth->second.At(static_cast<int>(p2d.xy.y()),
                                           static_cast<int>(p2d.xy.x()));
      EXPECT_NEAR(depth, xc.z(), 2.0 * xc.z() / camera.CalibrationMatrix()(0, 0) + 1e-6)
          << image.name << " at " << p2d.xy.transpose();
    }
  }

  // Ground truth: every view, consistent with the masks' foreground and the cameras.
  const GroundTruthCameras cameras = ReadGroundTruthCameras(gt_path);
  ASSERT_EQ(cameras.names.size(), 4u);
  EXPECT_EQ(cameras.width, 160);
  EXPECT_EQ(cameras.height, 107);
  for (size_t i = 0; i < cameras.names.size(); ++i) {
    const Image& image = ws.ImageByName(cameras.names[i]);
    EXPECT_LT((image.R() - cameras.R[i]).norm(), 1e-9);
    EXPECT_LT((image.t() - cameras.t[i]).norm(), 1e-9);
    const GroundTruthView view = ReadGroundTruthView(gt_path, cameras.names[i]);
    ASSERT_EQ(view.depth.Width(), 160);
    ASSERT_EQ(view.depth.Height(), 107);
    const FloatMap mask = ReadMask(ws.MaskPath(cameras.names[i]), 160, 107);
    int hair = 0, skin = 0;
    for (int r = 0; r < 107; ++r) {
      for (int c = 0; c < 160; ++c) {
        const uint8_t l = view.label[static_cast<size_t>(r) * 160 + c];
        const float d = view.depth.At(r, c);
        EXPECT_EQ(l != kLabelBackground, d > 0.0f);
        if (l != kLabelBackground) {
          EXPECT_GT(mask.At(r, c), 0.5f);
          EXPECT_GT(d, 0.4f);
          EXPECT_LT(d, 0.8f);
        }
        hair += l == kLabelHair;
        skin += l == kLabelSkin;
      }
    }
    EXPECT_GT(hair, 500) << cameras.names[i];
  }
  const GroundTruthStrands strands = ReadGroundTruthStrands(gt_path);
  EXPECT_EQ(strands.NumStrands(), 1500u);
  EXPECT_EQ(strands.offsets.back(), static_cast<int64_t>(strands.points.size()));
  for (const char* f : {"meta.json", "vis/g0_c_depth.png", "vis/g0_c_label.png"}) {
    EXPECT_TRUE(ExistsFile(JoinPaths(gt_path, f))) << f;
  }
  // The hair centre is the camera target: it projects to the principal point of g0_c.
  const Image& g0c = ws.ImageByName("g0_c.png");
  const Eigen::Vector3d hc = g0c.R() * cameras.hair_centre + g0c.t();
  EXPECT_NEAR(hc.x() / hc.z(), 0.0, 1e-6);
  EXPECT_NEAR((g0c.ProjectionCenter() - cameras.hair_centre).norm(), 0.6, 1e-6);
  fs::remove_all(path);
}

// Same seed, same bytes (the .npz archives' zip headers carry libzip's time stamps, so their
// arrays are compared); another seed, other images.
// Rendering a set's own strands (--strands_path its gt/) gives the same geometry: the same
// strands in gt/, the same cameras and true depths and labels; only the strands' colours
// differ (they are not stored).
TEST(Synthesize, RendersGivenStrandsAsTheirOwnSet) {
  const std::string first_path = MakeTestDir("strands_first");
  RunSynthesize(SmallOptions(first_path));
  const std::string gt_first = JoinPaths(first_path, "gt");
  const std::string second_path = MakeTestDir("strands_second");
  SynthesizeOptions options = SmallOptions(second_path);
  options.strands_path = gt_first;
  options.num_strands = 7;  // not used with strands_path
  const SynthesizeResult result = RunSynthesize(options);
  EXPECT_EQ(result.num_strands, 1500);
  const std::string gt_second = JoinPaths(second_path, "gt");
  const GroundTruthStrands a = ReadGroundTruthStrands(gt_first);
  const GroundTruthStrands b = ReadGroundTruthStrands(gt_second);
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.offsets, b.offsets);
  const GroundTruthCameras cameras = ReadGroundTruthCameras(gt_second);
  const GroundTruthCameras cameras_first = ReadGroundTruthCameras(gt_first);
  ASSERT_EQ(cameras.names, cameras_first.names);
  ASSERT_EQ(cameras.names.size(), 4u);
  for (size_t i = 0; i < cameras.names.size(); ++i) {
    EXPECT_EQ(cameras.R[i], cameras_first.R[i]);
    EXPECT_EQ(cameras.t[i], cameras_first.t[i]);
  }
  for (const std::string& name : cameras.names) {
    const GroundTruthView va = ReadGroundTruthView(gt_first, name);
    const GroundTruthView vb = ReadGroundTruthView(gt_second, name);
    EXPECT_EQ(va.depth.Data(), vb.depth.Data()) << name;
    EXPECT_EQ(va.label, vb.label) << name;
  }
  EXPECT_NE(ReadBytes(JoinPaths(first_path, "dense", "images", "g0_c.png")),
            ReadBytes(JoinPaths(second_path, "dense", "images", "g0_c.png")));

  options.strands_path = JoinPaths(first_path, "no_such_folder");
  options.output_path = MakeTestDir("strands_third");
  const std::string message = testing_util::ErrorOf([&] { RunSynthesize(options); });
  // Named as the option's folder, not as a ground truth folder the user never gave.
  EXPECT_NE(message.find("--strands_path"), std::string::npos) << message;
  EXPECT_NE(message.find(options.strands_path), std::string::npos) << message;
  EXPECT_EQ(testing_util::NumEntriesIn(options.output_path), 0);
  // A folder without the strands fails once the set's staging folder exists: the failed run
  // leaves nothing (not even its hidden staging folder), so the same command with the right
  // strands runs at once.
  options.strands_path = MakeTestDir("strands_empty_gt");
  const std::string empty_message = testing_util::ErrorOf([&] { RunSynthesize(options); });
  EXPECT_NE(empty_message.find("strands_points.npy"), std::string::npos) << empty_message;
  EXPECT_EQ(testing_util::NumEntriesIn(options.output_path), 0);
  options.strands_path = gt_first;
  RunSynthesize(options);
  EXPECT_EQ(testing_util::NumEntriesIn(options.output_path), 3);  // dense, gt, sparse
}

TEST(Synthesize, DeterministicForASeed) {
  const std::string a = MakeTestDir("det_a"), b = MakeTestDir("det_b"), c = MakeTestDir("det_c");
  SynthesizeOptions options = SmallOptions(a);
  options.style = HairStyle::kCurly;
  options.rig = CameraRigType::kHandheld;
  options.num_views = 3;
  RunSynthesize(options);
  options.output_path = b;
  RunSynthesize(options);
  options.output_path = c;
  options.seed = 6;
  RunSynthesize(options);
  // Not over a set that is there: its maps would stay beside the new images.
  const std::string before = ReadBytes(JoinPaths(c, "gt", "cameras.npz"));
  options.seed = 5;
  EXPECT_EQ(testing_util::ErrorOf([&] { RunSynthesize(options); }),
            "synthesize: " + JoinPaths(c, "dense") +
                " exists already: give a new --output_path (or remove the old set first)");
  EXPECT_EQ(ReadBytes(JoinPaths(c, "gt", "cameras.npz")), before);
  const std::vector<std::string> files = ListFiles(a);
  ASSERT_EQ(files, ListFiles(b));
  EXPECT_GT(files.size(), 20u);
  for (const std::string& f : files) {
    const std::string pa = JoinPaths(a, f), pb = JoinPaths(b, f);
    if (f.size() > 4 && f.substr(f.size() - 4) == ".npz") {
      const auto za = ReadNpz(pa), zb = ReadNpz(pb);
      ASSERT_EQ(za.size(), zb.size()) << f;
      for (const auto& [key, array] : za) {
        EXPECT_EQ(array.dtype, zb.at(key).dtype) << f << " " << key;
        EXPECT_EQ(array.shape, zb.at(key).shape) << f << " " << key;
        EXPECT_TRUE(array.data == zb.at(key).data) << f << " " << key;
      }
    } else {
      EXPECT_TRUE(ReadBytes(pa) == ReadBytes(pb)) << f;
    }
  }
  EXPECT_EQ(ListFiles(c), files);
  EXPECT_FALSE(ReadBytes(JoinPaths(a, "dense/images/h00.png")) ==
               ReadBytes(JoinPaths(c, "dense/images/h00.png")));
  for (const auto& p : {a, b, c}) fs::remove_all(p);
}

}  // namespace
}  // namespace hairmvs
