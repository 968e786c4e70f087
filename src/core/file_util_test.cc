#include "src/core/file_util.h"

#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "src/core/logging.h"
#include "src/core/test_util.h"

namespace hairmvs {
namespace {

using testing_util::MakeTestDir;

// COLMAP's joining: a second part that starts with a separator (an image name such as
// "/x/a.png" in a model) still goes under the first.
TEST(FileUtil, JoinPathsAppendsAsColmapDoes) {
  EXPECT_EQ(JoinPaths("ws", "images", "a.png"), "ws/images/a.png");
  EXPECT_EQ(JoinPaths("ws/images", "/x/a.png"), "ws/images/x/a.png");
  EXPECT_EQ(JoinPaths("/ws/", "//x/a.png"), "/ws/x/a.png");
  EXPECT_EQ(JoinPaths("ws", ""), "ws");
  EXPECT_EQ(JoinPaths("", "/x/a.png"), "/x/a.png");
}

// A name near the file system's 255-byte limit (a photo's name with ".png" added, as a mask)
// is written: its temporary name is shortened to fit, not longer than the name itself.
TEST(FileUtil, AtomicWriteOfALongName) {
  const std::string dir = MakeTestDir("long_name");
  const std::string path = JoinPaths(dir, std::string(246, 'x') + ".jpg.png");
  WriteFileAtomically(path, [](std::ostream& out) { out << "mask"; });
  EXPECT_EQ(ReadTextFile(path), "mask");
  EXPECT_EQ(testing_util::NumEntriesIn(dir), 1);
  // A name of two-byte characters (é): written too.
  std::string accented;
  for (int i = 0; i < 120; ++i) accented += "\xc3\xa9";
  const std::string accented_path = JoinPaths(dir, accented + ".png");
  WriteFileAtomically(accented_path, [](std::ostream& out) { out << "mask"; });
  EXPECT_EQ(ReadTextFile(accented_path), "mask");
}

TEST(FileUtil, AtomicWriteReplacesOnlyWhenComplete) {
  const std::string dir = MakeTestDir("atomic");
  const std::string path = JoinPaths(dir, "sub", "file.txt");
  WriteFileAtomically(path, [](std::ostream& out) { out << "first"; });
  EXPECT_EQ(ReadTextFile(path), "first");
  // A writer that fails half-way leaves the old content and no temporary file behind.
  EXPECT_THROW(WriteFileAtomically(path,
                                   [](std::ostream& out) {
                                     out << "half";
                                     throw std::runtime_error("interrupted");
                                   }),
               std::runtime_error);
  EXPECT_EQ(ReadTextFile(path), "first");
  EXPECT_EQ(testing_util::NumEntriesIn(ParentPath(path)), 1);
}

// Interrupted in the middle of two nested writes (a stream and a named temporary), the process
// dies of the signal, and both temporaries are gone while the old target is whole. Each case
// runs in a child process (a death test), so the handlers do not stay installed here.
TEST(FileUtil, InterruptRemovesTemporariesInFlight) {
  const std::string dir = MakeTestDir("interrupt");
  const std::string kept = JoinPaths(dir, "kept.txt");
  const std::string named = JoinPaths(dir, "named.png");
  WriteFileAtomically(kept, [](std::ostream& out) { out << "old"; });
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
    EXPECT_EXIT(
        {
          RemoveTemporaryFilesOnInterrupt();
          WriteFileAtomically(kept, [&](std::ostream& out) {
            out << "half" << std::flush;
            WritePathAtomically(named, [&](const std::string& tmp_path) {
              WriteFileAtomically(tmp_path, [](std::ostream& o) { o << "x"; });
              // kept.txt, its temporary, the named temporary and the latter's own one
              // (renamed over it already): 3 files, so both writes are in flight.
              if (testing_util::NumEntriesIn(dir) != 3) std::_Exit(3);
              std::raise(signal_number);
            });
          });
          std::_Exit(4);  // not reached: the signal ends the process
        },
        ::testing::KilledBySignal(signal_number), "");
    EXPECT_EQ(testing_util::NumEntriesIn(dir), 1) << "signal " << signal_number;
    EXPECT_EQ(ReadTextFile(kept), "old");
  }
}

// A signal the caller ignores (nohup's SIGHUP) stays ignored.
TEST(FileUtil, InterruptHandlersLeaveIgnoredSignalsIgnored) {
  EXPECT_EXIT(
      {
        std::signal(SIGHUP, SIG_IGN);
        RemoveTemporaryFilesOnInterrupt();
        std::raise(SIGHUP);
        std::_Exit(0);
      },
      ::testing::ExitedWithCode(0), "");
}

// Past `ulimit -f` a write fails with a message and leaves the old file, rather than SIGXFSZ
// ending the process with its temporary left.
TEST(FileUtil, FileSizeLimitFailsTheWriteNotTheProcess) {
  const std::string dir = MakeTestDir("size_limit");
  const std::string kept = JoinPaths(dir, "kept.txt");
  WriteFileAtomically(kept, [](std::ostream& out) { out << "old"; });
  EXPECT_EXIT(
      {
        RemoveTemporaryFilesOnInterrupt();
        rlimit limit{};
        getrlimit(RLIMIT_FSIZE, &limit);
        limit.rlim_cur = 1000;
        setrlimit(RLIMIT_FSIZE, &limit);
        const std::string message = testing_util::ErrorOf([&] {
          WriteFileAtomically(kept, [](std::ostream& out) { out << std::string(5000, 'x'); });
        });
        std::_Exit(message.find("File too large") != std::string::npos &&
                           testing_util::NumEntriesIn(dir) == 1
                       ? 0
                       : 5);
      },
      ::testing::ExitedWithCode(0), "");
  EXPECT_EQ(ReadTextFile(kept), "old");
}

// Files written as a unit: a writer that throws after another's temporary is complete leaves
// every old target byte for byte and no temporary; once all writers succeed, all are replaced.
TEST(FileUtil, WriteFilesAtomicallyReplacesAllOrNone) {
  const std::string dir = MakeTestDir("unit");
  const std::string first = JoinPaths(dir, "cameras.bin");
  const std::string second = JoinPaths(dir, "images.bin");
  const std::string old_first("old\0cameras", 11), old_second = "old images\n";
  WriteFileAtomically(first, [&](std::ostream& out) { out << old_first; });
  WriteFileAtomically(second, [&](std::ostream& out) { out << old_second; });
  EXPECT_THROW(WriteFilesAtomically({{first, [](std::ostream& out) { out << "new cameras"; }},
                                     {second,
                                      [](std::ostream& out) {
                                        out << "half" << std::flush;
                                        throw std::runtime_error("disk full");
                                      }}}),
               std::runtime_error);
  EXPECT_EQ(ReadTextFile(first), old_first);
  EXPECT_EQ(ReadTextFile(second), old_second);
  EXPECT_EQ(testing_util::NumEntriesIn(dir), 2);

  WriteFilesAtomically({{first, [](std::ostream& out) { out << "new cameras"; }},
                        {second, [](std::ostream& out) { out << "new images"; }, false},
                        {JoinPaths(dir, "sub", "points3D.bin"),
                         [](std::ostream& out) { out << "new points"; }}});
  EXPECT_EQ(ReadTextFile(first), "new cameras");
  EXPECT_EQ(ReadTextFile(second), "new images");
  EXPECT_EQ(ReadTextFile(JoinPaths(dir, "sub", "points3D.bin")), "new points");
  EXPECT_EQ(testing_util::NumEntriesIn(dir), 3);  // the two files and sub/

  // A folder in the way of the first rename: it is named, the second target keeps its old
  // bytes, and the second temporary does not stay behind.
  const std::string folder = JoinPaths(dir, "folder.bin");
  CreateDirs(folder);
  const std::string message = testing_util::ErrorOf([&] {
    WriteFilesAtomically({{folder, [](std::ostream& out) { out << "x"; }},
                          {second, [](std::ostream& out) { out << "newer images"; }}});
  });
  EXPECT_NE(message.find("to " + folder + ": Is a directory"), std::string::npos) << message;
  EXPECT_EQ(ReadTextFile(second), "new images");
  EXPECT_EQ(testing_util::NumEntriesIn(dir), 4);
}

// With the last file marking the unit whole (a depth map beside its normal map): a rename that
// fails before the last one leaves the unit without its last file, never the old last file
// beside new others; a write that fails before any rename leaves everything as it was.
TEST(FileUtil, WriteFilesAtomicallyWithTheLastFileMarkingTheUnit) {
  const std::string dir = MakeTestDir("marked_unit");
  const std::string normals = JoinPaths(dir, "normals.bin");
  const std::string depths = JoinPaths(dir, "depths.bin");
  auto write = [](const char* text) {
    return [text](std::ostream& out) { out << text; };
  };
  WriteFilesAtomically({{normals, write("old normals")}, {depths, write("old depths")}}, true);
  EXPECT_EQ(ReadTextFile(depths), "old depths");
  EXPECT_THROW(WriteFilesAtomically({{normals, write("new normals")},
                                     {depths,
                                      [](std::ostream& out) {
                                        out << "half" << std::flush;
                                        throw std::runtime_error("disk full");
                                      }}},
                                    true),
               std::runtime_error);
  EXPECT_EQ(ReadTextFile(normals), "old normals");
  EXPECT_EQ(ReadTextFile(depths), "old depths");
  // The first rename fails (a folder where the normals go): the old depths are gone.
  const std::string blocked = JoinPaths(dir, "blocked.bin");
  CreateDirs(blocked);
  EXPECT_THROW(WriteFilesAtomically({{blocked, write("new normals")}, {depths, write("new")}},
                                    true),
               Error);
  EXPECT_FALSE(ExistsFile(depths));
  EXPECT_EQ(testing_util::NumEntriesIn(dir), 2);  // normals.bin and the folder
}

// Copies as a unit (undistort_masks' masks): all are copied, empty files too, or, when a
// source cannot be read, none, the source named.
TEST(FileUtil, CopyFilesAtomicallyCopiesAllOrNone) {
  const std::string dir = MakeTestDir("copy_unit");
  const std::string a = JoinPaths(dir, "a.png"), empty = JoinPaths(dir, "empty.png");
  WriteFileAtomically(a, [](std::ostream& out) { out << std::string("\x89PNG\0x", 6); });
  WriteFileAtomically(empty, [](std::ostream&) {});
  const std::string to_a = JoinPaths(dir, "out", "a.png");
  const std::string to_empty = JoinPaths(dir, "out", "empty.png");
  CopyFilesAtomically({{a, to_a}, {empty, to_empty}});
  EXPECT_EQ(ReadTextFile(to_a), std::string("\x89PNG\0x", 6));
  EXPECT_EQ(ReadTextFile(to_empty), "");
  const std::string message = testing_util::ErrorOf([&] {
    CopyFilesAtomically({{empty, to_a}, {JoinPaths(dir, "missing.png"), to_empty}});
  });
  EXPECT_NE(message.find("Cannot open " + JoinPaths(dir, "missing.png")), std::string::npos)
      << message;
  EXPECT_EQ(ReadTextFile(to_a), std::string("\x89PNG\0x", 6));  // not replaced
  EXPECT_EQ(testing_util::NumEntriesIn(JoinPaths(dir, "out")), 2);
}

// A write that cannot start or cannot be renamed into place says why, and leaves no temporary.
TEST(FileUtil, FailedWriteSaysWhy) {
  const std::string dir = MakeTestDir("failed_write");
  auto write = [](std::ostream& out) { out << "data"; };
  // A folder where no file can be made, even by root.
  const std::string in_proc = "/proc/hairmvs_failed_write.txt";
  std::string message = testing_util::ErrorOf([&] { WriteFileAtomically(in_proc, write); });
  EXPECT_EQ(message.find("Cannot write " + in_proc + ": "), 0u) << message;
  // A name over the file system's 255 bytes: its temporary is shortened to fit, the rename
  // cannot be.
  const std::string long_path = JoinPaths(dir, std::string(256, 'a') + ".txt");
  message = testing_util::ErrorOf([&] { WriteFileAtomically(long_path, write); });
  EXPECT_NE(message.find("to " + long_path + ": File name too long"), std::string::npos)
      << message;
  // A folder in the way of the rename.
  const std::string folder = JoinPaths(dir, "target.txt");
  CreateDirs(folder);
  message = testing_util::ErrorOf([&] { WriteFileAtomically(folder, write); });
  EXPECT_NE(message.find("Cannot rename"), std::string::npos) << message;
  EXPECT_NE(message.find("to " + folder + ": Is a directory"), std::string::npos) << message;
  EXPECT_TRUE(ExistsDir(folder));
  EXPECT_EQ(testing_util::NumEntriesIn(dir), 1);
}

// A scratch folder that a stopped run left on this host is removed by the next one of the same
// prefix; those of running processes, of other hosts and of other prefixes are kept.
TEST(FileUtil, ScratchDirRemovesTheFoldersOfEndedRunsOfThisHost) {
  const std::string dir = MakeTestDir("scratch");
  std::string host;
  {
    const ScratchDir probe(dir, ".set.staging");
    host = probe.Path().substr(probe.Path().rfind('@') + 1);
    EXPECT_FALSE(host.empty()) << probe.Path();
    EXPECT_TRUE(ExistsDir(probe.Path()));
  }
  EXPECT_EQ(testing_util::NumEntriesIn(dir), 0);
  const pid_t ended = fork();
  if (ended == 0) _exit(0);
  ASSERT_EQ(waitpid(ended, nullptr, 0), ended);
  const std::string gone = std::to_string(ended);
  const std::vector<std::string> removed = {".set.staging" + gone + "_0@" + host,
                                            ".set.staging" + gone + "_3"};  // no host: this one
  const std::vector<std::string> kept = {
      ".set.staging1_0@" + host,                     // init's: running
      ".set.staging" + gone + "_0@another-" + host,  // its process cannot be looked up
      ".set.staging" + gone + "_0@" + host.substr(0, host.find('~')) + "~1",  // another PID
                                                                             // namespace's
      ".other.staging" + gone + "_0@" + host,        // another prefix
      ".set.stagingx_0@" + host};                    // not a scratch name
  for (const auto* names : {&removed, &kept}) {
    for (const std::string& name : *names) CreateDirs(JoinPaths(dir, name, "images"));
  }
  {
    const ScratchDir scratch(dir, ".set.staging");
    for (const std::string& name : removed) EXPECT_FALSE(ExistsDir(JoinPaths(dir, name))) << name;
    for (const std::string& name : kept) EXPECT_TRUE(ExistsDir(JoinPaths(dir, name))) << name;
    const std::string own = JoinPaths(dir, ".set.staging" + std::to_string(getpid()) + "_");
    EXPECT_EQ(scratch.Path().rfind(own, 0), 0u) << scratch.Path();
    EXPECT_EQ(scratch.Path().substr(scratch.Path().size() - host.size() - 1), "@" + host);
  }
  EXPECT_EQ(testing_util::NumEntriesIn(dir), static_cast<int>(kept.size()));
}

// A temporary's name holds its process, a token drawn per process and its host, so that jobs in
// containers (the same pids) writing into one workspace do not share names. The first write
// into a folder removes the temporaries that killed runs of this host left there; those of
// running processes and of other hosts, and other hidden files, are kept.
TEST(FileUtil, AtomicWriteRemovesTheTemporariesOfEndedRunsOfThisHost) {
  const std::string dir = MakeTestDir("ended_temporaries");
  // This host's tag, "<host name>~<PID namespace>", from a temporary written elsewhere (the
  // first write into a folder cleans it, once).
  std::string probe;
  WritePathAtomically(JoinPaths(MakeTestDir("ended_temporaries_probe"), "p.bin"),
                      [&](const std::string& tmp_path) {
                        probe = tmp_path;
                        std::ofstream(tmp_path) << "p";
                      });
  const size_t at = probe.rfind('@');
  ASSERT_NE(at, std::string::npos) << probe;
  const std::string host = probe.substr(at + 1, probe.size() - at - 1 - 4);  // less ".bin"
  char host_name[256] = {};
  ASSERT_EQ(gethostname(host_name, sizeof(host_name) - 1), 0);
  EXPECT_EQ(host.rfind(host_name, 0), 0u) << host;
  const pid_t ended = fork();
  if (ended == 0) _exit(0);
  ASSERT_EQ(waitpid(ended, nullptr, 0), ended);
  const std::string gone = std::to_string(ended);
  const std::vector<std::string> removed = {
      ".a.tmp" + gone + "_3_0123abcd@" + host + ".bin",
      ".b.tmp" + gone + "_0_89abcdef@" + host,  // no extension
      ".c.png.tmp" + gone + "_7.png",           // the older form, without token and host
      ".d.tmp" + gone + "_2",                   // the older form of a name without extension
      ".e.tmp" + gone + "_1_0123abcd@" + host_name + ".bin"};  // the host name alone (older)
  const std::vector<std::string> kept = {
      ".a.tmp1_0_0123abcd@" + host + ".bin",                 // init's: running
      ".a.tmp" + gone + "_0_0123abcd@another-" + host + ".bin",  // another host's
      ".a.tmp" + gone + "_0_0123abcd@" + host_name + "~1.bin",  // another PID namespace's
      ".a.tmpx_0.bin",                                         // not a temporary's name
      ".hidden"};
  for (const auto* names : {&removed, &kept}) {
    for (const std::string& name : *names) {
      std::ofstream(JoinPaths(dir, name)) << "left";
    }
  }
  std::string temporary;
  WritePathAtomically(JoinPaths(dir, "new.bin"), [&](const std::string& tmp_path) {
    temporary = tmp_path;
    std::ofstream(tmp_path) << "new";
  });
  for (const std::string& name : removed) EXPECT_FALSE(ExistsFile(JoinPaths(dir, name))) << name;
  for (const std::string& name : kept) EXPECT_TRUE(ExistsFile(JoinPaths(dir, name))) << name;
  EXPECT_EQ(ReadTextFile(JoinPaths(dir, "new.bin")), "new");
  const std::string own = JoinPaths(dir, ".new.tmp" + std::to_string(getpid()) + "_");
  EXPECT_EQ(temporary.rfind(own, 0), 0u) << temporary;
  const std::string end = "@" + host + ".bin";
  ASSERT_GT(temporary.size(), end.size());
  EXPECT_EQ(temporary.substr(temporary.size() - end.size()), end) << temporary;
}

// A folder this process may not write to is named before any work; a missing one is made.
// A staged output appears in its folder whole or not at all.
TEST(FileUtil, StagingDirMovesEntriesIntoPlaceOrRemovesThem) {
  const std::string dir = MakeTestDir("staging");
  {
    StagingDir staging(dir, "set");
    WriteFileAtomically(JoinPaths(staging.Path(), "dense", "a.txt"),
                        [](std::ostream& out) { out << "a"; });
    WriteFileAtomically(JoinPaths(staging.Path(), "gt.txt"), [](std::ostream& out) { out << "b"; });
    EXPECT_EQ(testing_util::NumEntriesIn(dir), 1);  // only the hidden staging folder
    staging.Commit({"dense", "gt.txt"});
  }
  EXPECT_EQ(ReadTextFile(JoinPaths(dir, "dense", "a.txt")), "a");
  EXPECT_EQ(ReadTextFile(JoinPaths(dir, "gt.txt")), "b");
  EXPECT_EQ(testing_util::NumEntriesIn(dir), 2);

  // Work that throws before the commit leaves nothing behind.
  EXPECT_THROW(
      {
        StagingDir staging(dir, "set");
        WriteFileAtomically(JoinPaths(staging.Path(), "other.txt"),
                            [](std::ostream& out) { out << "c"; });
        throw std::runtime_error("rendering failed");
      },
      std::runtime_error);
  EXPECT_EQ(testing_util::NumEntriesIn(dir), 2);

  // An entry that exists in the folder already is named, and nothing is moved.
  StagingDir staging(dir, "set");
  WriteFileAtomically(JoinPaths(staging.Path(), "new.txt"), [](std::ostream& out) { out << "n"; });
  WriteFileAtomically(JoinPaths(staging.Path(), "gt.txt"), [](std::ostream& out) { out << "x"; });
  const std::string exists = testing_util::ErrorOf([&] { staging.Commit({"new.txt", "gt.txt"}); });
  EXPECT_NE(exists.find(JoinPaths(dir, "gt.txt") + " exists already"), std::string::npos)
      << exists;
  EXPECT_FALSE(ExistsFile(JoinPaths(dir, "new.txt")));
  EXPECT_EQ(ReadTextFile(JoinPaths(dir, "gt.txt")), "b");
  const std::string missing = testing_util::ErrorOf([&] { staging.Commit({"sparse"}); });
  EXPECT_NE(missing.find("sparse into place: it was not written"), std::string::npos) << missing;

  // With replace: an existing file is replaced, and an entry's folders are made.
  StagingDir replacing(dir, "pictures");
  WriteFileAtomically(JoinPaths(replacing.Path(), "gt.txt"), [](std::ostream& out) { out << "r"; });
  WriteFileAtomically(JoinPaths(replacing.Path(), "sub", "a.txt"),
                      [](std::ostream& out) { out << "s"; });
  replacing.Commit({"gt.txt", "sub/a.txt"}, /*replace=*/true);
  EXPECT_EQ(ReadTextFile(JoinPaths(dir, "gt.txt")), "r");
  EXPECT_EQ(ReadTextFile(JoinPaths(dir, "sub", "a.txt")), "s");
}

TEST(FileUtil, RequireWritableDir) {
  const std::string dir = JoinPaths(MakeTestDir("writable"), "stereo", "depth_maps");
  RequireWritableDir(dir, "depth map folder");
  EXPECT_TRUE(ExistsDir(dir));
  // procfs refuses writes to a process's folder even to root (the tests may run as root, to
  // whom a chmod'ed folder is writable).
  const std::string message =
      testing_util::ErrorOf([] { RequireWritableDir("/proc/self", "depth map folder"); });
  EXPECT_EQ(message.rfind("Cannot write to the depth map folder /proc/self: ", 0), 0u)
      << message;
}

TEST(FileUtil, MissingFileErrorNamesThePath) {
  try {
    RequireFile("/nonexistent/hairmvs/cameras.bin", "camera file");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/hairmvs/cameras.bin"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("camera file"), std::string::npos);
  }
}

// A folder where a file is expected, or the other way round, is named as such, not as missing.
TEST(FileUtil, FileWhereAFolderIsExpectedIsNamed) {
  const std::string dir = MakeTestDir("kinds");
  const std::string file = JoinPaths(dir, "fused.ply");
  WriteFileAtomically(file, [](std::ostream& out) { out << "ply"; });
  EXPECT_EQ(testing_util::ErrorOf([&] { RequireDir(file, "workspace folder"); }),
            "The workspace folder " + file + " is a file, not a folder");
  EXPECT_EQ(testing_util::ErrorOf([&] { RequireFile(dir, "camera file"); }),
            "The camera file " + dir + " is a folder, not a file");
}

TEST(FileUtil, SplitAndStrip) {
  EXPECT_EQ(StripWhitespace("  a b \r\n"), "a b");
  const auto parts = SplitString("a, b;c", ",;");
  ASSERT_EQ(parts.size(), 3u);
  EXPECT_EQ(StripWhitespace(parts[1]), "b");
  EXPECT_EQ(parts[2], "c");
  EXPECT_EQ(JoinStrings({"a", "b", "c"}, ", "), "a, b, c");
  EXPECT_EQ(JoinStrings({"a"}, ", "), "a");
  EXPECT_EQ(JoinStrings({}, ", "), "");
  EXPECT_EQ(JoinFirstNames({"a", "b", "c"}, 3), "a, b, c");
  EXPECT_EQ(JoinFirstNames({"a", "b", "c"}, 2), "a, b, ...");
}

// Control bytes quoted from a file are escaped; newlines, tabs and UTF-8 stay.
TEST(FileUtil, PrintableTextEscapesControlBytes) {
  EXPECT_EQ(PrintableText("a\x1b[2J\x1b]0;t\x07" "b\n\tc\x7f"),
            "a\\x1b[2J\\x1b]0;t\\x07b\n\tc\\x7f");
  EXPECT_EQ(PrintableText(std::string("a\0b", 3)), "a\\x00b");
  EXPECT_EQ(PrintableText("h\xc3\xa4ir"), "h\xc3\xa4ir");
}

}  // namespace
}  // namespace hairmvs
