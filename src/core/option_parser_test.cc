#include "src/core/option_parser.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <utility>
#include <vector>

#include "src/core/enum_names.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/test_util.h"

namespace hairmvs {
namespace {

enum class Solver { kGraphCuts, kSemiGlobal };
constexpr std::pair<Solver, const char*> kSolverNames[] = {{Solver::kGraphCuts, "graph_cuts"},
                                                           {Solver::kSemiGlobal, "semi_global"}};
std::string ToString(Solver s) { return EnumName(kSolverNames, s); }
bool FromString(const std::string& text, Solver* s) {
  return EnumFromName(kSolverNames, text, s);
}

// Both directions come from the one table; an unknown name is refused and leaves the value.
TEST(EnumNames, NamesAndValuesFromOneTable) {
  EXPECT_EQ(ToString(Solver::kSemiGlobal), "semi_global");
  EXPECT_EQ(ToString(Solver::kGraphCuts), "graph_cuts");
  Solver solver = Solver::kGraphCuts;
  EXPECT_TRUE(FromString("semi_global", &solver));
  EXPECT_EQ(solver, Solver::kSemiGlobal);
  EXPECT_FALSE(FromString("semi-global", &solver));
  EXPECT_EQ(solver, Solver::kSemiGlobal);
}

struct ToyOptions {
  double lambda = 0.5;
  int num_levels = 3;
  bool write_png = false;
  Solver solver = Solver::kGraphCuts;
  template <typename Visitor>
  void ForEachField(Visitor&& v) {
    v("lambda", &lambda, "smoothness weight");
    v("num_levels", &num_levels, "levels");
    v("write_png", &write_png, "pictures");
    v("solver", &solver, "graph_cuts|semi_global");
  }
};

std::vector<char*> Argv(std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  return argv;
}

TEST(OptionParser, ParsesSectionsInColmapStyle) {
  ToyOptions options;
  std::string workspace;
  OptionParser parser("toy", "a toy command");
  parser.Add("workspace_path", &workspace, "workspace", /*required=*/true);
  parser.AddSection("Toy", &options);
  std::vector<std::string> args = {"hairmvs", "toy", "--workspace_path", "/w",
                                   "--Toy.lambda", "2.5", "--Toy.write_png", "1",
                                   "--Toy.solver", "semi_global"};
  auto argv = Argv(args);
  ASSERT_TRUE(parser.Parse(static_cast<int>(argv.size()), argv.data()));
  EXPECT_EQ(workspace, "/w");
  EXPECT_DOUBLE_EQ(options.lambda, 2.5);
  EXPECT_EQ(options.num_levels, 3);
  EXPECT_TRUE(options.write_png);
  EXPECT_EQ(options.solver, Solver::kSemiGlobal);
  EXPECT_TRUE(parser.WasGiven("Toy.lambda"));
  EXPECT_FALSE(parser.WasGiven("Toy.num_levels"));
  EXPECT_NE(parser.Values().find("Toy.solver = semi_global"), std::string::npos);
  // Numbers print as typed: the fewest digits (6 at least) that read back as the same value.
  for (const auto& [value, text] : std::vector<std::pair<double, std::string>>{
           {0.12, "0.12"}, {0.3333333, "0.3333333"}, {1.0 / 3, "0.3333333333333333"},
           {1e-4, "0.0001"}, {2.5, "2.5"}}) {
    options.lambda = value;
    EXPECT_NE(parser.Values().find("Toy.lambda = " + text + "\n"), std::string::npos)
        << parser.Values();
  }
}

// colmap's --project_path: the .ini's options apply where the command line gives none; its
// sections of other commands are passed over; its options of our sections that have no effect
// are named in one warning. Booleans take any case, as colmap's do.
TEST(OptionParser, ProjectFileAsColmapsWithTheCommandLineWinning) {
  const std::string dir = testing_util::MakeTestDir("project_path");
  const std::string ini = JoinPaths(dir, "project.ini");
  WriteFileAtomically(ini, [](std::ostream& out) {
    out << "log_level=2\nworkspace_path=/from/ini\n[SiftExtraction]\nmax_num_features="
           "8192\n[Toy]\nlambda=0.75\nnum_levels=5\nwrite_png=True\nwindow_radius=5\n"
           "gpu_index=-1\n";
  });
  ToyOptions options;
  std::string workspace;
  OptionParser parser("toy", "a toy command");
  parser.Add("workspace_path", &workspace, "workspace", /*required=*/true);
  parser.AddSection("Toy", &options);
  parser.AddIgnored("Toy.gpu_index", "no such thing here");
  parser.AddIgnored("log_level", "logs always");
  parser.AddProjectPath({"Toy"});
  std::vector<std::string> args = {"hairmvs", "toy", "--project_path", ini, "--Toy.num_levels",
                                   "2"};
  auto argv = Argv(args);
  ::testing::internal::CaptureStderr();
  ASSERT_TRUE(parser.Parse(static_cast<int>(argv.size()), argv.data()));
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(workspace, "/from/ini");  // a required option, given by the file
  EXPECT_DOUBLE_EQ(options.lambda, 0.75);
  EXPECT_EQ(options.num_levels, 2);  // the command line's
  EXPECT_TRUE(options.write_png);
  EXPECT_TRUE(parser.WasGiven("Toy.lambda"));
  EXPECT_NE(log.find("2 of its options have no effect"), std::string::npos) << log;
  EXPECT_NE(log.find("log_level, Toy.gpu_index"), std::string::npos) << log;
  EXPECT_NE(log.find("1 of its options are unknown to hairmvs and colmap 3.8 (a typo, or "
                     "another colmap version's?), not applied: Toy.window_radius"),
            std::string::npos)
      << log;
  EXPECT_EQ(log.find("--log_level is ignored"), std::string::npos) << log;
  EXPECT_TRUE(parser.FromProjectFile("Toy.lambda"));
  EXPECT_FALSE(parser.FromProjectFile("Toy.num_levels"));  // the command line's
  EXPECT_NE(log.find("options read from it: workspace_path=/from/ini, Toy.lambda=0.75, "
                     "Toy.write_png=True\n"),
            std::string::npos)
      << log;
  EXPECT_EQ(log.find("max_num_features"), std::string::npos) << log;
  EXPECT_EQ(log.find("--Toy.gpu_index is ignored"), std::string::npos) << log;

  // A key of one of the command's own sections that is none of its options (a typo) is
  // refused, naming the file and the key, as the command line refuses it; other commands'
  // sections are still passed over.
  {
    WriteFileAtomically(ini, [](std::ostream& out) {
      out << "[SiftExtraction]\nmax_num_features=8192\n[Extra]\nlamda=1\nlambda=2\n";
    });
    ToyOptions extra;
    OptionParser typo("toy", "a toy command");
    typo.AddSection("Toy", &options);
    typo.AddSection("Extra", &extra);
    typo.AddProjectPath({"Toy"});
    const std::string message =
        testing_util::ErrorOf([&] { typo.Parse(static_cast<int>(argv.size()), argv.data()); });
    EXPECT_NE(message.find("--project_path " + ini + ": unknown option Extra.lamda (see hairmvs "
                           "toy -h)"),
              std::string::npos)
        << message;
  }
  // A missing file and a malformed one are named.
  for (const auto& [text, why] : std::vector<std::pair<std::string, std::string>>{
           {"", "Missing project file"}, {"[Toy\nlambda=1\n", "project.ini"}}) {
    if (text.empty()) {
      std::filesystem::remove(ini);
    } else {
      WriteFileAtomically(ini, [&](std::ostream& out) { out << text; });
    }
    OptionParser again("toy", "a toy command");
    again.AddSection("Toy", &options);
    again.AddProjectPath({"Toy"});
    const std::string message =
        testing_util::ErrorOf([&] { again.Parse(static_cast<int>(argv.size()), argv.data()); });
    EXPECT_NE(message.find(why), std::string::npos) << message;
    EXPECT_NE(message.find(ini), std::string::npos) << message;
  }
}

TEST(OptionParser, RejectsUnknownOptionsAndBadValues) {
  ToyOptions options;
  OptionParser parser("toy", "a toy command");
  parser.AddSection("Toy", &options);
  std::vector<std::string> unknown = {"hairmvs", "toy", "--Toy.nope", "1"};
  auto argv = Argv(unknown);
  EXPECT_THROW(parser.Parse(static_cast<int>(argv.size()), argv.data()), Error);

  OptionParser parser2("toy", "a toy command");
  parser2.AddSection("Toy", &options);
  std::vector<std::string> bad = {"hairmvs", "toy", "--Toy.solver", "simulated_annealing"};
  auto argv2 = Argv(bad);
  try {
    parser2.Parse(static_cast<int>(argv2.size()), argv2.data());
    ADD_FAILURE() << "a bad enum value was accepted";
  } catch (const Error& e) {
    // The message names the value, the option and, through its help, the accepted names.
    const std::string message = e.what();
    EXPECT_NE(message.find("'simulated_annealing'"), std::string::npos) << message;
    EXPECT_NE(message.find("--Toy.solver"), std::string::npos) << message;
    EXPECT_NE(message.find("graph_cuts|semi_global"), std::string::npos) << message;
  }
}

// A list of names: separators and spaces between them; empty (nothing given) is no names,
// but separators alone are an error, not "all".
TEST(OptionParser, NameLists) {
  for (const auto& [text, expected] :
       std::vector<std::pair<std::string, std::vector<std::string>>>{
           {"a.png, b.png;c.png", {"a.png", "b.png", "c.png"}}, {"", {}}, {" ", {}}}) {
    std::vector<std::string> names = {"old"};
    OptionParser parser("toy", "a toy command");
    parser.Add("image_names", &names, "views");
    std::vector<std::string> args = {"hairmvs", "toy", "--image_names", text};
    auto argv = Argv(args);
    ASSERT_TRUE(parser.Parse(static_cast<int>(argv.size()), argv.data())) << text;
    EXPECT_EQ(names, expected) << text;
  }
  std::vector<std::string> names;
  OptionParser parser("toy", "a toy command");
  parser.Add("image_names", &names, "views");
  std::vector<std::string> args = {"hairmvs", "toy", "--image_names", ",,,"};
  auto argv = Argv(args);
  const std::string message = testing_util::ErrorOf(
      [&] { parser.Parse(static_cast<int>(argv.size()), argv.data()); });
  EXPECT_NE(message.find("--image_names"), std::string::npos) << message;
  EXPECT_NE(message.find("',,,'"), std::string::npos) << message;
}

// A word that is not an option (a second value, a forgotten "--") and a number that is not
// finite are errors naming what was typed, not dropped or taken.
TEST(OptionParser, RejectsStrayWordsAndNonFiniteNumbers) {
  for (const auto& [typed, stray] :
       {std::pair<std::vector<std::string>, std::string>{{"--Toy.num_levels", "2", "5"}, "5"},
        {{"--Toy.num_levels=2", "Toy.lambda=3"}, "Toy.lambda=3"},
        {{"--Toy.num_levels=2", "--", "--Toy.lambda", "3"}, "--Toy.lambda"}}) {
    ToyOptions options;
    OptionParser parser("toy", "a toy command");
    parser.AddSection("Toy", &options);
    std::vector<std::string> args = {"hairmvs", "toy"};
    args.insert(args.end(), typed.begin(), typed.end());
    auto argv = Argv(args);
    const std::string error = testing_util::ErrorOf(
        [&] { parser.Parse(static_cast<int>(argv.size()), argv.data()); });
    EXPECT_NE(error.find("hairmvs toy: unexpected word '" + stray + "'"), std::string::npos)
        << error;
  }
  for (const std::string value : {"inf", "-inf", "nan"}) {
    ToyOptions options;
    OptionParser parser("toy", "a toy command");
    parser.AddSection("Toy", &options);
    std::vector<std::string> args = {"hairmvs", "toy", "--Toy.lambda", value};
    auto argv = Argv(args);
    const std::string error = testing_util::ErrorOf(
        [&] { parser.Parse(static_cast<int>(argv.size()), argv.data()); });
    EXPECT_NE(error.find("for --Toy.lambda: not a finite number"), std::string::npos) << error;
  }
}

TEST(OptionParser, MissingRequiredOptionIsAnError) {
  std::string workspace;
  OptionParser parser("toy", "a toy command");
  parser.Add("workspace_path", &workspace, "workspace", /*required=*/true);
  std::vector<std::string> args = {"hairmvs", "toy"};
  auto argv = Argv(args);
  EXPECT_THROW(parser.Parse(static_cast<int>(argv.size()), argv.data()), Error);
}

// boost stores every option's value at notify(), defaults too: a second option on one variable
// would overwrite what was given to the first (template_fusion's --num_threads did so to
// --TemplateFusion.num_threads). Binding one twice is refused when the parser is built.
TEST(OptionParser, OneVariableIsBoundToOneOption) {
  ToyOptions options;
  OptionParser parser("toy", "a toy command");
  parser.AddSection("Toy", &options);
  const std::string error = testing_util::ErrorOf(
      [&] { parser.Add("num_levels", &options.num_levels, "short form"); });
  EXPECT_NE(error.find("--num_levels and --Toy.num_levels are bound to one variable"),
            std::string::npos)
      << error;
}

}  // namespace
}  // namespace hairmvs
