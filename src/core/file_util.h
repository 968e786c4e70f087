#pragma once
// Files: paths, existence checks that throw with the path, and atomic writes.
// Nothing is lost: every output is written under a temporary name in the same folder and
// renamed over the target only once complete, so an existing file is never half-overwritten.

#include <functional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace hairmvs {

std::string JoinPaths(const std::string& a, const std::string& b);
template <typename... T>
std::string JoinPaths(const std::string& a, const std::string& b, const T&... rest) {
  return JoinPaths(JoinPaths(a, b), rest...);
}

bool ExistsFile(const std::string& path);
// Anything at `path`: a file, a folder or another kind (a link is followed).
bool Exists(const std::string& path);
bool ExistsDir(const std::string& path);
// Throws hairmvs::Error naming `what` and `path` when missing.
void RequireFile(const std::string& path, const std::string& what = "file");
void RequireDir(const std::string& path, const std::string& what = "folder");
// Creates the folder and its parents (no error if it exists).
void CreateDirs(const std::string& path);
// CreateDirs, then throws hairmvs::Error naming `what`, `path` and the reason unless this
// process may write there: checked before long work whose outputs go there.
void RequireWritableDir(const std::string& path, const std::string& what = "folder");
std::string ParentPath(const std::string& path);
// Whether `inner` is `outer` or lies inside it, after resolving links, `.` and `..` (of the
// parts that exist): an output that would land in an input.
bool IsSameOrInside(const std::string& inner, const std::string& outer);
std::string ReadTextFile(const std::string& path);
std::vector<std::string> ReadLines(const std::string& path);
std::string StripWhitespace(const std::string& s);
// `text` with its control bytes (but newlines and tabs) written as \xNN: a message that quotes
// a file's bytes cannot move the terminal's cursor or retitle its window.
std::string PrintableText(const std::string& text);
// `s` with its ASCII letters in lower case (option values and file extensions in any case).
std::string ToLower(std::string s);
std::vector<std::string> SplitString(const std::string& s, const std::string& delims);
// The parts with `separator` between them: "a, b" from {"a", "b"} and ", ".
std::string JoinStrings(const std::vector<std::string>& parts, const std::string& separator);
// The first `max_parts` parts joined with ", ", and ", ..." after them if there are more: a
// message's list of names that stays one line.
std::string JoinFirstNames(const std::vector<std::string>& parts, size_t max_parts = 5);

// Writes `path` atomically: `write` fills a stream for a temporary file next to `path`,
// which is then renamed to `path`. Parent folders are created. If `write` throws, the
// temporary file is removed and the exception propagates; `path` is untouched.
void WriteFileAtomically(const std::string& path,
                         const std::function<void(std::ostream&)>& write, bool binary = true);
// One file of WriteFilesAtomically: `write` fills the stream of `path`'s temporary.
struct FileToWrite {
  std::string path;
  std::function<void(std::ostream&)> write;
  bool binary = true;
};
// Writes files that are only valid together (a model's cameras, images and points3D) as a
// unit: every temporary is written first, and only once all are complete are they renamed over
// their targets, in order. If any `write` throws, every temporary is removed and the exception
// propagates; no target is touched. The renames are the one step that is not atomic as a whole
// (POSIX has no rename of several files): a rename that fails leaves the targets before it
// replaced, and removes the temporaries left. With `last_marks_complete`, the last file is what
// tells a reader the unit is whole: its old version is removed once every temporary is complete,
// before the first rename, so that a run stopped between the renames leaves the unit without its
// last file (to be made again) rather than new files beside an old one.
void WriteFilesAtomically(const std::vector<FileToWrite>& files,
                          bool last_marks_complete = false);
// For writers that need a file name (OpenCV's imwrite): `write` receives a temporary path
// with the same extension as `path`.
void WritePathAtomically(const std::string& path,
                         const std::function<void(const std::string& tmp_path)>& write);
// `from`'s bytes written to `to` with WriteFileAtomically.
void CopyFileAtomically(const std::string& from, const std::string& to);
// Each pair's `from` copied to its `to` as one unit (WriteFilesAtomically).
void CopyFilesAtomically(const std::vector<std::pair<std::string, std::string>>& from_to);

// A folder `<parent>/<prefix><pid>_<n>@<host>` (made empty, with `parent`), removed with
// everything in it when destroyed. A process that a signal ends cannot remove it (the interrupt
// handler removes files, which is async-signal-safe, not folder trees), so each new one first
// removes the folders of the same prefix in `parent` whose process has ended, naming each in
// the log; those of other hosts (a folder shared over the network) or of other PID namespaces
// of this host (containers: <host> is "<host name>~<PID namespace inode>") are left, since their
// processes cannot be looked up from here.
class ScratchDir {
 public:
  ScratchDir(const std::string& parent, const std::string& prefix);
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::string& Path() const { return path_; }

 private:
  std::string path_;
};

// A hidden ScratchDir `.<name>.staging<pid>_<n>@<host>` inside `parent`, in which an output
// that is only valid as a whole (a synthesized data set: images, masks, model and truth) is
// built: Commit() renames its named entries into `parent`, where none of them may exist yet;
// destroyed uncommitted (the work threw), it is removed with everything in it, so a failed run
// leaves nothing that the next one would have to refuse or overwrite. One that a killed process
// left is removed by the next run (ScratchDir).
class StagingDir {
 public:
  StagingDir(const std::string& parent, const std::string& name);
  StagingDir(const StagingDir&) = delete;
  StagingDir& operator=(const StagingDir&) = delete;

  // The folder to write into.
  const std::string& Path() const { return scratch_.Path(); }
  // Moves each of `entries` (names inside Path(), which may hold folders) to `parent`/<entry>,
  // in order. Throws hairmvs::Error naming the entry when one is missing here or, unless
  // `replace`, exists already in `parent` (checked for all before any is moved), or when a
  // rename fails. With `replace`, a file there is replaced (renamed over) and the entry's
  // folders are made.
  void Commit(const std::vector<std::string>& entries, bool replace = false);

 private:
  std::string parent_;
  ScratchDir scratch_;
  bool committed_ = false;
};

// Installs handlers for SIGINT, SIGTERM and SIGHUP (those not ignored) that remove the
// temporary files of the writes above still in flight, then let the signal end the process as
// it would have: a run stopped with Ctrl-C or by a cluster scheduler leaves no hidden
// temporaries in the workspace, and every target is either its old or its new file. Also
// ignores SIGXFSZ, so that a file past `ulimit -f` fails its write with a message, as a full
// disk does, rather than ending the process. The hairmvs binary calls it first thing.
void RemoveTemporaryFilesOnInterrupt();

}  // namespace hairmvs
