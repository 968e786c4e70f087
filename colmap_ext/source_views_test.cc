#include "colmap_ext/source_views.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "colmap_ext/test_util.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace hairmvs {
namespace {

using testing_util::ErrorOf;
using testing_util::MakeTestDir;
using testing_util::WriteTestWorkspace;

// Views with identity rotation at `centres` (camera y points down, so +y is "below"), named
// by `names`; points on the plane z = 2; point k is seen by the views whose bit is set in
// `visibility[k]`.
Reconstruction MakeRig(const std::vector<Eigen::Vector3d>& centres,
                       const std::vector<std::string>& names,
                       const std::vector<unsigned>& visibility) {
  testing_util::PlaneModelOptions options;
  options.centres = centres;
  options.plane_z_m = 2.0;
  options.num_points = static_cast<int>(visibility.size());
  Reconstruction r = testing_util::MakePlaneModel(options);
  for (auto& [id, image] : r.images) image.name = names[id - 1];
  for (auto& [pid, point] : r.points3D) {
    std::vector<TrackElement> track;
    for (const TrackElement& el : point.track) {
      if (visibility[pid - 1] & (1u << (el.image_id - 1))) track.push_back(el);
    }
    point.track = track;
  }
  return r;
}

Workspace WriteAndRead(const std::string& name, const Reconstruction& model) {
  const std::string dir = MakeTestDir(name);
  WriteTestWorkspace(dir, model);
  return Workspace::Read(dir);
}

// The defaults pass; angles beyond a half turn (views cannot be further apart) are refused by
// name, as are the other bounds.
TEST(SourceViews, OptionsAreChecked) {
  SourceViewOptions options;
  std::string error;
  EXPECT_TRUE(options.Check(&error)) << error;
  options.max_triangulation_angle_deg = 181;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("max_triangulation_angle_deg must be at most 180"), std::string::npos)
      << error;
  options = SourceViewOptions();
  options.t_group_max_view_angle_deg = 200;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("t_group_max_view_angle_deg must be in (0, 180]"), std::string::npos)
      << error;
  options = SourceViewOptions();
  options.max_num_source_views = 0;
  EXPECT_FALSE(options.Check(&error));
  EXPECT_NE(error.find("max_num_source_views"), std::string::npos) << error;
}

TEST(SourceViews, EpipolarSpreadPrefersADifferentDirection) {
  // ref, three horizontal neighbours sharing 40 points, one vertical sharing 20.
  std::vector<unsigned> visibility(40, 0b01111u);
  for (int k = 0; k < 20; ++k) visibility[k] |= 0b10000u;
  const Reconstruction model =
      MakeRig({{0, 0, 0}, {0.1, 0, 0}, {0.2, 0, 0}, {-0.1, 0, 0}, {0, 0.2, 0}},
              {"ref.png", "h1.png", "h2.png", "h3.png", "v1.png"}, visibility);
  const Workspace ws = WriteAndRead("spread", model);
  SourceViewOptions options;
  options.max_num_source_views = 2;
  options.epipolar_spread_weight = 0;  // COLMAP's ranking: shared points only
  std::vector<SourceViewSelection> s = SelectSourceViews(ws, options);
  ASSERT_EQ(s.size(), 5u);
  EXPECT_EQ(s[0].reference, "ref.png");
  EXPECT_EQ(s[0].sources, (std::vector<std::string>{"h1.png", "h2.png"}));
  EXPECT_FALSE(s[0].gantry_t_group);
  options.epipolar_spread_weight = 2;
  s = SelectSourceViews(ws, options);
  EXPECT_EQ(s[0].sources, (std::vector<std::string>{"h1.png", "v1.png"}));
  ASSERT_EQ(s[0].epipolar_direction_deg.size(), 2u);
  EXPECT_NEAR(s[0].epipolar_direction_deg[0], 0.0, 1e-6);
  EXPECT_NEAR(s[0].epipolar_direction_deg[1], 90.0, 1e-6);
  EXPECT_EQ(s[0].shared_points, (std::vector<int>{40, 20}));
  EXPECT_NE(s[0].reason.find("epipolar"), std::string::npos) << s[0].reason;
}

TEST(SourceViews, GantryTGroupIsRecognisedAndChosenFirst) {
  // Centre, left, right, bottom (the paper's rig) and a far view sharing more points.
  std::vector<unsigned> visibility(40, 0b11111u);
  const Reconstruction model =
      MakeRig({{0, 0, 0}, {-0.1, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}, {0.4, 0.3, 0}},
              {"c.png", "l.png", "r.png", "b.png", "far.png"}, visibility);
  const Workspace ws = WriteAndRead("tgroup", model);
  SourceViewOptions options;
  options.max_num_source_views = 4;
  const std::vector<SourceViewSelection> s = SelectSourceViews(ws, options);
  ASSERT_EQ(s.size(), 5u);
  EXPECT_TRUE(s[0].gantry_t_group) << s[0].reason;
  ASSERT_GE(s[0].sources.size(), 3u);
  EXPECT_EQ(std::vector<std::string>(s[0].sources.begin(), s[0].sources.begin() + 3),
            (std::vector<std::string>{"l.png", "r.png", "b.png"}));
  EXPECT_NE(s[0].reason.find("gantry T group"), std::string::npos);
  // From the left view, the others are all to the right or diagonal: no T group.
  EXPECT_FALSE(s[1].gantry_t_group) << s[1].reason;
  // Only 2 sources wanted: a T group cannot be used whole.
  options.max_num_source_views = 2;
  EXPECT_FALSE(SelectSourceViews(ws, options)[0].gantry_t_group);
}

TEST(SourceViews, TriangulationAngleTestsAndConfig) {
  std::vector<unsigned> visibility(30, 0b111u);
  // near.png is 1 mm away: about 0.03 degrees, below the 1 degree test.
  const Reconstruction model = MakeRig({{0, 0, 0}, {0.001, 0, 0}, {0.1, 0, 0}},
                                       {"a.png", "near.png", "far.png"}, visibility);
  const std::string dir = MakeTestDir("config");
  WriteTestWorkspace(dir, model);
  const Workspace ws = Workspace::Read(dir);
  SourceViewOptions options;
  std::vector<SourceViewSelection> s = SelectSourceViews(ws, options);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].sources, (std::vector<std::string>{"far.png"}));
  EXPECT_NEAR(s[0].triangulation_angle_deg[0], 2.86, 0.05);

  // The cfg is honoured: explicit list (separators , and ;), __all__, __auto__ with comments.
  WriteFileAtomically(JoinPaths(dir, "stereo", "patch-match.cfg"), [](std::ostream& out) {
    out << "# a comment\n a.png \nnear.png; far.png\n\nfar.png\n__all__\n"
           "near.png\n# between\n__auto__, 7\n";
  });
  s = SelectSourceViews(ws, options);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].sources, (std::vector<std::string>{"near.png", "far.png"}));
  EXPECT_EQ(s[1].reference, "far.png");
  EXPECT_EQ(s[1].sources, (std::vector<std::string>{"a.png", "near.png"}));
  EXPECT_EQ(s[2].reference, "near.png");
  EXPECT_EQ(s[2].sources, (std::vector<std::string>{"far.png"}));  // a.png fails the angle test
  // Without the cfg: the automatic selection of every view, as before the cfg was written.
  options.use_config = false;
  const std::vector<SourceViewSelection> automatic = SelectSourceViews(ws, options);
  ASSERT_EQ(automatic.size(), 3u);
  EXPECT_EQ(automatic[0].reference, "a.png");
  EXPECT_EQ(automatic[0].sources, (std::vector<std::string>{"far.png"}));
  options.use_config = true;
  options.config_path = JoinPaths(dir, "missing.cfg");
  EXPECT_NE(ErrorOf([&] { SelectSourceViews(ws, options); }).find("missing.cfg"),
            std::string::npos);
  options.config_path = dir;  // a folder given: said to be one, not missing
  EXPECT_EQ(ErrorOf([&] { SelectSourceViews(ws, options); }),
            "The patch-match config (config_path) " + dir + " is a folder, not a file");
  // A folder in stereo/patch-match.cfg's place is an error, not automatic source views.
  options.config_path.clear();
  const std::string cfg = JoinPaths(dir, "stereo", "patch-match.cfg");
  std::filesystem::remove(cfg);
  CreateDirs(cfg);
  const std::string folder = ErrorOf([&] { SelectSourceViews(ws, options); });
  EXPECT_NE(folder.find("The patch-match config " + cfg + " is a folder, not a file"),
            std::string::npos)
      << folder;
}

// A model image that images/ lacks (`colmap image_undistorter --image_list_path`) is no
// source: automatic and __all__ lists leave it out, and a config that names it is refused with
// its file and line.
TEST(SourceViews, ImagesWithoutAFileAreNoSources) {
  std::vector<unsigned> visibility(30, 0b111u);
  const Reconstruction model = MakeRig({{0, 0, 0}, {0.1, 0, 0}, {-0.1, 0, 0}},
                                       {"a.png", "gone.png", "c.png"}, visibility);
  const std::string dir = MakeTestDir("sources_without_file");
  WriteTestWorkspace(dir, model);
  std::filesystem::remove(JoinPaths(dir, "images", "gone.png"));
  const Workspace ws = Workspace::Read(dir);
  SourceViewOptions options;
  std::vector<SourceViewSelection> s = SelectSourceViews(ws, options);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].reference, "a.png");
  EXPECT_EQ(s[0].sources, (std::vector<std::string>{"c.png"}));
  EXPECT_EQ(s[1].sources, (std::vector<std::string>{"a.png"}));
  const std::string cfg = JoinPaths(dir, "stereo", "patch-match.cfg");
  WriteFileAtomically(cfg, [](std::ostream& out) { out << "a.png\n__all__\n"; });
  s = SelectSourceViews(ws, options);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].sources, (std::vector<std::string>{"c.png"}));
  WriteFileAtomically(cfg, [](std::ostream& out) { out << "a.png\ngone.png, c.png\n"; });
  std::string error = ErrorOf([&] { SelectSourceViews(ws, options); });
  EXPECT_NE(error.find("Image `gone.png` (" + cfg + ":2) is in the model of " + dir +
                       " but not in its images folder"),
            std::string::npos)
      << error;
  WriteFileAtomically(cfg, [](std::ostream& out) { out << "gone.png\n__auto__, 2\n"; });
  error = ErrorOf([&] { SelectSourceViews(ws, options); });
  EXPECT_NE(error.find("Image `gone.png` (" + cfg + ":2)"), std::string::npos) << error;
}

// A list longer than max_num_source_views, explicit or __all__, keeps the views sharing the
// most points (ties: the listed order), and the estimate and the geometric pass use just those.
// Empty tokens are skipped, as COLMAP's CSVToVector skips them.
TEST(SourceViews, LongListsKeepTheViewsSharingTheMostPoints) {
  // ref sees all 40 points; o2 / o4 / o3 / o1 share 40 / 30 / 20 / 10 of them with it.
  std::vector<unsigned> visibility;
  for (int k = 0; k < 40; ++k) {
    visibility.push_back(1u | (k < 10 ? 2u : 0u) | 4u | (k < 20 ? 8u : 0u) | (k < 30 ? 16u : 0u));
  }
  const Reconstruction model =
      MakeRig({{0, 0, 0}, {0.1, 0, 0}, {0.2, 0, 0}, {0.3, 0, 0}, {0.4, 0, 0}},
              {"ref.png", "o1.png", "o2.png", "o3.png", "o4.png"}, visibility);
  const std::string dir = MakeTestDir("long_lists");
  WriteTestWorkspace(dir, model);
  const Workspace ws = Workspace::Read(dir);
  WriteFileAtomically(JoinPaths(dir, "stereo", "patch-match.cfg"), [](std::ostream& out) {
    out << "ref.png\n o1.png, o2.png,, o3.png; o4.png, \no1.png\n__all__,\n"
           "o2.png\n o3.png ,\no3.png\n , ;\n";
  });
  SourceViewOptions options;
  options.max_num_source_views = 2;
  const std::vector<SourceViewSelection> s = SelectSourceViews(ws, options);
  ASSERT_EQ(s.size(), 3u);  // o3.png lists no source: dropped, as COLMAP drops it
  EXPECT_EQ(s[0].reference, "ref.png");
  EXPECT_EQ(s[0].sources, (std::vector<std::string>{"o2.png", "o4.png"}));
  EXPECT_EQ(s[0].shared_points, (std::vector<int>{40, 30}));
  ASSERT_EQ(s[0].triangulation_angle_deg.size(), 2u);
  ASSERT_EQ(s[0].epipolar_direction_deg.size(), 2u);
  EXPECT_NE(s[0].reason.find("the 2 of 4 sharing the most sparse points kept"),
            std::string::npos)
      << s[0].reason;
  EXPECT_EQ(s[1].reference, "o1.png");  // shares 10 points with each: the listed order
  EXPECT_EQ(s[1].sources, (std::vector<std::string>{"ref.png", "o2.png"}));
  EXPECT_EQ(s[2].reference, "o2.png");
  EXPECT_EQ(s[2].sources, (std::vector<std::string>{"o3.png"}));
  EXPECT_EQ(s[2].reason.find("kept"), std::string::npos) << s[2].reason;
  options.max_num_source_views = 4;
  EXPECT_EQ(SelectSourceViews(ws, options)[0].sources,
            (std::vector<std::string>{"o1.png", "o2.png", "o3.png", "o4.png"}));
}

// Views wider than max_triangulation_angle_deg come last, also when the T group holds some.
TEST(SourceViews, WideViewsOnlyWhenNoNarrowOneIsLeft) {
  // A T group 0.1 m from c (2.9 degrees), a diagonal view 0.35 m away sharing all points, and a
  // diagonal one 0.05 m away (1.4 degrees) sharing half.
  std::vector<unsigned> visibility(40, 0b011111u);
  for (int k = 0; k < 20; ++k) visibility[k] |= 0b100000u;
  const Reconstruction model = MakeRig(
      {{0, 0, 0}, {-0.1, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}, {0.25, 0.25, 0}, {0.035, -0.035, 0}},
      {"c.png", "l.png", "r.png", "b.png", "wide.png", "narrow.png"}, visibility);
  const Workspace ws = WriteAndRead("wide_last", model);
  SourceViewOptions options;
  options.max_triangulation_angle_deg = 2.0;  // the T group's views are wide too
  options.max_num_source_views = 4;
  std::vector<SourceViewSelection> s = SelectSourceViews(ws, options);
  ASSERT_TRUE(s[0].gantry_t_group) << s[0].reason;
  EXPECT_EQ(s[0].sources, (std::vector<std::string>{"l.png", "r.png", "b.png", "narrow.png"}))
      << s[0].reason;
  options.max_num_source_views = 5;
  s = SelectSourceViews(ws, options);
  EXPECT_EQ(s[0].sources,
            (std::vector<std::string>{"l.png", "r.png", "b.png", "narrow.png", "wide.png"}));
}

TEST(SourceViews, MalformedConfigLinesNameFileAndLine) {
  const Reconstruction model = MakeRig({{0, 0, 0}, {0.1, 0, 0}}, {"a.png", "b.png"}, {3, 3});
  const std::string dir = MakeTestDir("bad_cfg");
  const std::string path = JoinPaths(dir, "patch-match.cfg");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"a.png\n__auto__\n", ":2: expected `__auto__, N`"},
      {"a.png\n__auto__, x\n", ":2: `__auto__, N` needs a positive integer"},
      {"a.png\n__auto__, 3, 4\n", ":2: expected `__auto__, N`"},
      {"a.png\n__auto__, 0\n", ":2: `__auto__, N` needs a positive integer"},
      {"a.png\nb.png, c.png\n", ":2: Image with name `c.png` does not exist"},
      {"z.png\nb.png\n", ":1: Image with name `z.png`"},
      {"a.png\nb.png\nb.png\n", "reference b.png has no sources line"},
      {"a.png\na.png\n", ":2: reference a.png lists itself"},
      {"a.png\nb.png, b.png\n", ":2: source b.png is listed twice"},
      {"a.png\n__all__, 2\n", ":2: `__all__` takes no arguments"},
  };
  for (const auto& [text, expected] : cases) {
    WriteFileAtomically(path, [&](std::ostream& out) { out << text; });
    const std::string error = ErrorOf([&] { ReadPatchMatchConfig(path, model); });
    EXPECT_NE(error.find(path), std::string::npos) << error;
    EXPECT_NE(error.find(expected), std::string::npos) << error;
  }
  const std::string fusion = JoinPaths(dir, "fusion.cfg");
  WriteFileAtomically(fusion, [](std::ostream& out) { out << "a.png\n# no\n"; });
  EXPECT_NE(ErrorOf([&] { ReadFusionConfig(fusion, model); }).find(fusion + ":2: comment"),
            std::string::npos);
  WriteFileAtomically(fusion, [](std::ostream& out) { out << "a.png\nq.png\n"; });
  EXPECT_NE(ErrorOf([&] { ReadFusionConfig(fusion, model); }).find("`q.png`"),
            std::string::npos);
}

TEST(SourceViews, ConfigWritersRoundTrip) {
  const Reconstruction model =
      MakeRig({{0, 0, 0}, {0.1, 0, 0}, {0.2, 0, 0}}, {"a.png", "b.png", "c.png"}, {7, 7});
  const std::string dir = MakeTestDir("cfg_io");
  std::vector<PatchMatchProblem> problems(3);
  problems[0].reference = "a.png";
  problems[0].kind = PatchMatchProblem::Kind::kExplicit;
  problems[0].sources = {"b.png", "c.png"};
  problems[1].reference = "b.png";
  problems[1].kind = PatchMatchProblem::Kind::kAll;
  problems[2].reference = "c.png";
  problems[2].kind = PatchMatchProblem::Kind::kAuto;
  problems[2].num_auto = 20;
  WritePatchMatchConfig(JoinPaths(dir, "pm.cfg"), problems);
  EXPECT_EQ(ReadTextFile(JoinPaths(dir, "pm.cfg")),
            "a.png\nb.png, c.png\nb.png\n__all__\nc.png\n__auto__, 20\n");
  const std::vector<PatchMatchProblem> read = ReadPatchMatchConfig(JoinPaths(dir, "pm.cfg"), model);
  ASSERT_EQ(read.size(), 3u);
  EXPECT_EQ(read[0].sources, problems[0].sources);
  EXPECT_EQ(read[1].kind, PatchMatchProblem::Kind::kAll);
  EXPECT_EQ(read[2].num_auto, 20);
  WriteFusionConfig(JoinPaths(dir, "fusion.cfg"), {"c.png", "a.png"});
  EXPECT_EQ(ReadFusionConfig(JoinPaths(dir, "fusion.cfg"), model),
            (std::vector<std::string>{"c.png", "a.png"}));
}

TEST(SourceViews, EpipolarDirection) {
  const Reconstruction model = MakeRig({{0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}, {0, 0, 0.1}},
                                       {"a.png", "x.png", "y.png", "z.png"}, {15});
  const Eigen::Vector2d centre(32, 24);
  EXPECT_NEAR(EpipolarDirectionRad(model, 1, 2, centre), 0.0, 1e-9);
  EXPECT_NEAR(EpipolarDirectionRad(model, 1, 3, centre), M_PI / 2, 1e-9);
  // A forward baseline: epipole at the image centre, lines radiate from it; at (42, 34) the
  // line points along the diagonal.
  EXPECT_NEAR(EpipolarDirectionRad(model, 1, 4, Eigen::Vector2d(42, 34)), M_PI / 4, 1e-9);
}

TEST(SourceViews, ViewsLookingTheSameWayAreWithinTheAngleOfTheReferencesAxis) {
  // Five views on a ring around the origin, turned about the vertical (camera y) axis by 0,
  // 20, 45, 60 and 120 degrees, all looking at the centre.
  const std::vector<double> turns_deg = {0, 20, 45, 60, 120};
  const std::vector<std::string> names = {"a.png", "b.png", "c.png", "d.png", "e.png"};
  Reconstruction model =
      MakeRig(std::vector<Eigen::Vector3d>(5, Eigen::Vector3d::Zero()), names, {31});
  for (auto& [id, image] : model.images) {
    image.cam_from_world_rotation = Eigen::Quaterniond(
        Eigen::AngleAxisd(turns_deg[id - 1] * M_PI / 180, Eigen::Vector3d::UnitY()));
    image.cam_from_world_translation = Eigen::Vector3d(0, 0, 1);  // the centre 1 m ahead
  }
  const Workspace ws = WriteAndRead("same_way", model);
  EXPECT_EQ(ViewsLookingTheSameWay(ws, "a.png", {}, 50),
            (std::vector<std::string>{"b.png", "c.png"}));
  // The angle is between the viewing directions, whichever way they turn: from d, a and e
  // are both 60 degrees away.
  EXPECT_EQ(ViewsLookingTheSameWay(ws, "d.png", {}, 50),
            (std::vector<std::string>{"b.png", "c.png"}));
  EXPECT_EQ(ViewsLookingTheSameWay(ws, "d.png", {}, 65),
            (std::vector<std::string>{"a.png", "b.png", "c.png", "e.png"}));
  // Views already chosen (the sources) are not repeated.
  EXPECT_EQ(ViewsLookingTheSameWay(ws, "a.png", {"b.png"}, 50),
            (std::vector<std::string>{"c.png"}));
  EXPECT_EQ(ViewsLookingTheSameWay(ws, "a.png", {}, 10), (std::vector<std::string>{}));
  EXPECT_EQ(ViewsLookingTheSameWay(ws, "a.png", {}, 180).size(), 4u);
  // The nearest of them in direction, in their given order: from a, b (20 degrees), c (45),
  // d (60), e (120).
  const std::vector<std::string> others = {"e.png", "d.png", "c.png", "b.png"};
  EXPECT_EQ(NearestInDirection(ws, "a.png", others, 2),
            (std::vector<std::string>{"c.png", "b.png"}));
  EXPECT_EQ(NearestInDirection(ws, "a.png", others, 3),
            (std::vector<std::string>{"d.png", "c.png", "b.png"}));
  EXPECT_EQ(NearestInDirection(ws, "a.png", others, 0), (std::vector<std::string>{}));
  EXPECT_EQ(NearestInDirection(ws, "a.png", others, 4), others);
  // From d: c (15 degrees), b (40), before a and e (60 both).
  EXPECT_EQ(NearestInDirection(ws, "d.png", {"e.png", "a.png", "b.png", "c.png"}, 2),
            (std::vector<std::string>{"b.png", "c.png"}));
}

TEST(DepthRange, ColmapRuleAndOverrides) {
  Reconstruction model = MakeRig({{0, 0, 0}, {0.1, 0, 0}}, {"a.png", "b.png"}, {});
  for (int k = 1; k <= 100; ++k) {
    Point3D p;
    p.point3D_id = k;
    p.xyz = Eigen::Vector3d(0.01 * k, 0, k);  // depth k in view a
    p.track = {{1, 0}};
    model.points3D[k] = p;
  }
  Point3D behind;
  behind.point3D_id = 1000;
  behind.xyz = Eigen::Vector3d(0, 0, -3);
  behind.track = {{1, 0}};
  model.points3D[1000] = behind;
  const DepthRange range = ComputeDepthRange(model, 1);
  EXPECT_EQ(range.num_points, 100);
  EXPECT_DOUBLE_EQ(range.min_m, 0.75 * 2);   // d[floor(0.01 * 100)] = d[1] = 2
  EXPECT_DOUBLE_EQ(range.max_m, 1.25 * 100);  // d[floor(0.99 * 100)] = d[99] = 100
  const DepthRange none = ComputeDepthRange(model, 2);
  EXPECT_EQ(none.num_points, 0);
  EXPECT_EQ(none.min_m, -1);
}

TEST(DepthRange, InsideTheMaskOnlyWhenEnoughPointsAreInside) {
  Reconstruction model = MakeRig({{0, 0, 0}, {0.1, 0, 0}}, {"a.png", "b.png"}, {});
  Image& a = model.images.at(1);
  a.points2D.clear();
  const int width = static_cast<int>(model.cameras.at(a.camera_id).width);
  const int height = static_cast<int>(model.cameras.at(a.camera_id).height);
  // 30 points: depths 1..15 seen in the left half of the image, 16..30 in the right half.
  for (int k = 1; k <= 30; ++k) {
    Point2D observation;
    observation.xy = Eigen::Vector2d(k <= 15 ? 2.5 : width - 2.5, height / 2.0);
    observation.point3D_id = k;
    a.points2D.push_back(observation);
    Point3D p;
    p.point3D_id = k;
    p.xyz = Eigen::Vector3d(0, 0, k);
    p.track = {{1, static_cast<uint32_t>(k - 1)}};
    model.points3D[k] = p;
  }
  FloatMap left_half(width, height, 1, 0.0f);
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width / 2; ++col) left_half.At(row, col) = 1.0f;
  }
  const DepthRange inside = ComputeDepthRange(model, 1, left_half, 10);
  EXPECT_TRUE(inside.inside_mask);
  EXPECT_EQ(inside.num_points, 15);
  EXPECT_DOUBLE_EQ(inside.max_m, 1.25 * 15);
  // Too few points inside: COLMAP's rule on all of them, not marked as inside the mask.
  const DepthRange fallback = ComputeDepthRange(model, 1, left_half, 16);
  EXPECT_FALSE(fallback.inside_mask);
  EXPECT_EQ(fallback.num_points, 30);
  EXPECT_FALSE(ComputeDepthRange(model, 1).inside_mask);
}

}  // namespace
}  // namespace hairmvs
