#include "src/core/file_util.h"

#include <limits.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <random>
#include <regex>
#include <set>
#include <sstream>

#include "src/core/logging.h"

namespace fs = std::filesystem;

namespace hairmvs {

// As COLMAP's JoinPaths (boost::filesystem's `/`, which appends): `b` goes under `a` even when
// it starts with a separator, as an image name in a model may: colmap image_undistorter writes
// the image "/x/a.png" to <workspace>/images/x/a.png and its depth maps under stereo/ alike,
// where std::filesystem's `/` would replace `a` with `b` and reach outside the workspace.
std::string JoinPaths(const std::string& a, const std::string& b) {
  if (a.empty()) return b;
  const size_t relative = b.find_first_not_of('/');
  if (relative == std::string::npos) return a;
  return (fs::path(a) / fs::path(b.substr(relative))).string();
}

bool ExistsFile(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

bool Exists(const std::string& path) {
  std::error_code ec;
  return fs::exists(path, ec);
}

bool ExistsDir(const std::string& path) {
  std::error_code ec;
  return fs::is_directory(path, ec);
}

void RequireFile(const std::string& path, const std::string& what) {
  THROW_IF(ExistsDir(path), "The " << what << " " << path << " is a folder, not a file");
  THROW_IF(!ExistsFile(path), "Missing " << what << ": " << path);
}

void RequireDir(const std::string& path, const std::string& what) {
  THROW_IF(ExistsFile(path), "The " << what << " " << path << " is a file, not a folder");
  THROW_IF(!ExistsDir(path), "Missing " << what << ": " << path);
}

void CreateDirs(const std::string& path) {
  if (path.empty()) return;
  std::error_code ec;
  fs::create_directories(path, ec);
  THROW_IF(ec && !ExistsDir(path), "Cannot create folder " << path << ": " << ec.message());
}

void RequireWritableDir(const std::string& path, const std::string& what) {
  CreateDirs(path);
  THROW_IF(access(path.c_str(), W_OK) != 0,
           "Cannot write to the " << what << " " << path << ": " << std::strerror(errno));
}

std::string ParentPath(const std::string& path) { return fs::path(path).parent_path().string(); }

bool IsSameOrInside(const std::string& inner, const std::string& outer) {
  const fs::path a = fs::weakly_canonical(inner);
  const fs::path b = fs::weakly_canonical(outer);
  auto ia = a.begin();
  for (auto ib = b.begin(); ib != b.end(); ++ib, ++ia) {
    if (ia == a.end() || *ia != *ib) return false;
  }
  return true;
}

std::string ReadTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  THROW_IF(!in, "Cannot open " << path);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> ReadLines(const std::string& path) {
  std::istringstream in(ReadTextFile(path));
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(line);
  }
  return lines;
}

std::string StripWhitespace(const std::string& s) {
  const char* ws = " \t\r\n\v\f";
  const size_t begin = s.find_first_not_of(ws);
  if (begin == std::string::npos) return "";
  const size_t end = s.find_last_not_of(ws);
  return s.substr(begin, end - begin + 1);
}

std::string ToLower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string PrintableText(const std::string& text) {
  std::string printable;
  printable.reserve(text.size());
  for (const char ch : text) {
    const auto byte = static_cast<unsigned char>(ch);
    if ((byte < 0x20 && ch != '\n' && ch != '\t') || byte == 0x7f) {
      char escaped[5];
      std::snprintf(escaped, sizeof(escaped), "\\x%02x", byte);
      printable += escaped;
    } else {
      printable += ch;
    }
  }
  return printable;
}

std::vector<std::string> SplitString(const std::string& s, const std::string& delims) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (true) {
    const size_t pos = s.find_first_of(delims, start);
    parts.push_back(s.substr(start, pos == std::string::npos ? std::string::npos : pos - start));
    if (pos == std::string::npos) break;
    start = pos + 1;
  }
  return parts;
}

std::string JoinFirstNames(const std::vector<std::string>& parts, size_t max_parts) {
  if (parts.size() <= max_parts) return JoinStrings(parts, ", ");
  return JoinStrings(std::vector<std::string>(parts.begin(), parts.begin() + max_parts), ", ") +
         ", ...";
}

std::string JoinStrings(const std::vector<std::string>& parts, const std::string& separator) {
  std::string joined;
  for (size_t i = 0; i < parts.size(); ++i) joined += (i ? separator : "") + parts[i];
  return joined;
}

namespace {

// The temporary files of the atomic writes in flight, for the interrupt handler. Slots are
// fixed buffers claimed with an atomic flag, so that the handler reads them without locks or
// allocation (only async-signal-safe calls run there). A write that finds every slot taken is
// simply not tracked: more than kNumSlots writes at once is far beyond this program's threads.
constexpr int kNumSlots = 256;  // a unit of WriteFilesAtomically holds one per file
enum SlotState : int { kFree = 0, kClaimed = 1, kTracked = 2 };
struct TemporarySlot {
  std::atomic<int> state{kFree};
  char path[PATH_MAX];
};
TemporarySlot temporary_slots[kNumSlots];

// Tracks one temporary file from before it is created until it is renamed or removed.
class TrackedTemporary {
 public:
  explicit TrackedTemporary(const std::string& tmp) {
    if (tmp.size() >= PATH_MAX) return;
    for (TemporarySlot& slot : temporary_slots) {
      int expected = kFree;
      if (slot.state.compare_exchange_strong(expected, kClaimed)) {
        std::memcpy(slot.path, tmp.c_str(), tmp.size() + 1);
        slot.state.store(kTracked);
        slot_ = &slot;
        return;
      }
    }
  }
  ~TrackedTemporary() {
    if (slot_ != nullptr) slot_->state.store(kFree);
  }
  TrackedTemporary(const TrackedTemporary&) = delete;
  TrackedTemporary& operator=(const TrackedTemporary&) = delete;

 private:
  TemporarySlot* slot_ = nullptr;
};

void RemoveTemporariesAndDie(int signal_number) {
  for (TemporarySlot& slot : temporary_slots) {
    // A name already renamed fails with ENOENT; names are unique to this process.
    if (slot.state.load() == kTracked) unlink(slot.path);
  }
  // Said rather than leaving the log cut mid-line (write: async-signal-safe).
  static constexpr char kStopped[] =
      "\nhairmvs: stopped by a signal; every file written is whole: run the same command again "
      "to finish (the stereo resumes with --OrientationStereo.skip_existing 1)\n";
  const ssize_t ignored = write(STDERR_FILENO, kStopped, sizeof(kStopped) - 1);
  (void)ignored;
  // SA_RESETHAND restored the default action: the signal, delivered again once this handler
  // returns, ends the process as it would have without the handler (exit status, core).
  raise(signal_number);
}

// The host name alone ("localhost" where there is none): the tag of the names written before the
// PID namespace was part of it, which count as this host's too.
const std::string& HostName() {
  static const std::string host_name = [] {  // the same for the process's life
    char name[256] = {};
    const bool named = gethostname(name, sizeof(name) - 1) == 0 && name[0] != '\0';
    return std::string(named ? name : "localhost");
  }();
  return host_name;
}

// This host and its PID namespace, "<host name>~<namespace inode>": a process id names one
// process only within both. Containers on one host may share its name but each have a PID
// namespace of their own, with the same pids, so a run looks up the processes of the files of
// its own host and namespace only.
const std::string& HostTag() {
  static const std::string host_tag = [] {  // the same for the process's life
    std::string tag = HostName();
    char link[64] = {};  // "pid:[4026531836]"
    const ssize_t length = readlink("/proc/self/ns/pid", link, sizeof(link) - 1);
    if (length > 0) {
      const std::string text(link, static_cast<size_t>(length));
      const size_t open = text.find('['), close = text.find(']');
      if (open != std::string::npos && close != std::string::npos && close > open + 1) {
        tag += "~" + text.substr(open + 1, close - open - 1);
      }
    }
    return tag;
  }();
  return host_tag;
}

// Eight hex digits drawn once per process: with the pid and the host tag, a temporary's name is
// unique to its process even among jobs on machines or in containers of one host name and
// namespace inode writing into one shared workspace.
const std::string& ProcessToken() {
  static const std::string token = [] {
    std::random_device random;
    char hex[9];
    std::snprintf(hex, sizeof(hex), "%08x", static_cast<unsigned>(random()));
    return std::string(hex);
  }();
  return token;
}

// Whether the process `pid` of this host has ended (not merely exited unreaped: kill still
// finds a zombie, so its files are left until the next run).
bool ProcessEnded(long pid) {
  return pid != getpid() && kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

// ".<stem>.tmp<pid>_<n>_<token>@<host tag><extension>" beside `path`: hidden, unique to this
// process (ProcessToken), with the process and HostTag that a later run needs to tell whether it
// was left by a run that was killed (RemoveTemporariesOfEndedRuns), and with the extension kept
// (OpenCV picks the image format by it). The stem is shortened where the name would pass the file
// system's 255-byte limit, which a long name near it otherwise would.
std::string TemporaryPathFor(const std::string& path) {
  static std::atomic<int> counter{0};
  constexpr size_t kMaxNameBytes = 255;
  const fs::path p(path);
  std::ostringstream suffix;
  suffix << ".tmp" << getpid() << "_" << counter++ << "_" << ProcessToken() << "@" << HostTag()
         << p.extension().string();
  std::string stem = p.stem().string();
  const size_t room = kMaxNameBytes - std::min(kMaxNameBytes, 1 + suffix.str().size());
  if (stem.size() > room) {
    // Cut before a UTF-8 continuation byte's lead, so that the name stays valid UTF-8.
    size_t cut = room;
    while (cut > 0 && (static_cast<unsigned char>(stem[cut]) & 0xC0) == 0x80) --cut;
    stem.resize(cut);
  }
  return (p.parent_path() / ("." + stem + suffix.str())).string();
}

// The process of this host (and PID namespace: HostTag) that made the temporary file `name`
// (TemporaryPathFor), or -1 for a name of another or no temporary's. A name of the older form
// without token and host, ".<stem>.tmp<pid>_<n><extension>", counts as this host's, as
// ScratchDir's do.
long TemporaryOwnerOnThisHost(const std::string& name, const std::string& host) {
  static const std::regex kCurrent(R"(\..*\.tmp([0-9]{1,9})_[0-9]+_[0-9a-f]{8})");
  static const std::regex kOlder(R"(\..*\.tmp([0-9]{1,9})_[0-9]+)");
  const std::string extension = fs::path(name).extension().string();
  // The host name alone: the form before the PID namespace was part of the tag.
  const std::string& host_name = HostName();
  std::smatch match;
  for (const std::string& end : {"@" + host + extension, "@" + host, "@" + host_name + extension,
                                 "@" + host_name}) {
    if (name.size() > end.size() && name.compare(name.size() - end.size(), end.size(), end) == 0) {
      const std::string front = name.substr(0, name.size() - end.size());
      if (std::regex_match(front, match, kCurrent)) return std::stol(match[1].str());
    }
  }
  if (name.find('@') != std::string::npos) return -1;
  // With its extension, or without one (where ".tmp<pid>_<n>" itself reads as the extension).
  for (const std::string& front : {name.substr(0, name.size() - extension.size()), name}) {
    if (std::regex_match(front, match, kOlder)) return std::stol(match[1].str());
  }
  return -1;
}

// Removes from `folder` the temporary files that runs of this host left when killed (SIGKILL
// by a scheduler or the OOM killer, which no handler sees), once per folder and process: the
// first write there. Those of running processes and of other hosts are left.
void RemoveTemporariesOfEndedRuns(const std::string& folder) {
  static std::mutex mutex;
  static std::set<std::string> done;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (!done.insert(folder).second) return;
  }
  const std::string host = HostTag();
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name[0] != '.' || !entry.is_regular_file(ec)) continue;
    const long pid = TemporaryOwnerOnThisHost(name, host);
    if (pid <= 0 || !ProcessEnded(pid)) continue;
    LOG(INFO) << "Removing " << entry.path().string() << ", left by a run (process " << pid
              << ") that was stopped";
    fs::remove(entry.path(), ec);
  }
}

void RenameOver(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    const std::string why = ec.message();
    fs::remove(tmp, ec);
    HAIRMVS_THROW("Cannot rename " << tmp << " to " << path << ": " << why);
  }
}

}  // namespace

void WriteFileAtomically(const std::string& path,
                         const std::function<void(std::ostream&)>& write, bool binary) {
  WriteFilesAtomically({{path, write, binary}});
}

void WriteFilesAtomically(const std::vector<FileToWrite>& files, bool last_marks_complete) {
  std::vector<std::string> tmps;
  // Each temporary is tracked from before it is created until the last rename.
  std::vector<std::unique_ptr<TrackedTemporary>> tracked;
  auto remove_temporaries_from = [&tmps](size_t first) {
    std::error_code ec;
    for (size_t i = first; i < tmps.size(); ++i) fs::remove(tmps[i], ec);
  };
  try {
    for (const FileToWrite& file : files) {
      CreateDirs(ParentPath(file.path));
      RemoveTemporariesOfEndedRuns(ParentPath(file.path));
      tmps.push_back(TemporaryPathFor(file.path));
      const std::string& tmp = tmps.back();
      tracked.push_back(std::make_unique<TrackedTemporary>(tmp));
      std::ofstream out(tmp, file.binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
      // errno says why the stream failed (the folder not writable, the disk full).
      THROW_IF(!out, "Cannot write " << file.path << ": " << std::strerror(errno)
                                     << " (temporary " << tmp << ")");
      file.write(out);
      out.flush();
      THROW_IF(!out, "Write failed for " << file.path << ": " << std::strerror(errno));
    }
  } catch (...) {
    remove_temporaries_from(0);
    throw;
  }
  if (last_marks_complete && !files.empty()) {
    std::error_code ec;
    fs::remove(files.back().path, ec);
    if (ec) {
      remove_temporaries_from(0);
      HAIRMVS_THROW("Cannot remove " << files.back().path << ": " << ec.message());
    }
  }
  for (size_t i = 0; i < files.size(); ++i) {
    try {
      RenameOver(tmps[i], files[i].path);
    } catch (...) {
      remove_temporaries_from(i + 1);
      throw;
    }
  }
}

void WritePathAtomically(const std::string& path,
                         const std::function<void(const std::string& tmp_path)>& write) {
  CreateDirs(ParentPath(path));
  RemoveTemporariesOfEndedRuns(ParentPath(path));
  const std::string tmp = TemporaryPathFor(path);
  const TrackedTemporary tracked(tmp);
  try {
    write(tmp);
    THROW_IF(!ExistsFile(tmp), "Write failed for " << path);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
  RenameOver(tmp, path);
}

void CopyFileAtomically(const std::string& from, const std::string& to) {
  CopyFilesAtomically({{from, to}});
}

void CopyFilesAtomically(const std::vector<std::pair<std::string, std::string>>& from_to) {
  std::vector<FileToWrite> files;
  for (const auto& [from, to] : from_to) {
    // Read when its temporary is written: one file's bytes in memory at a time.
    files.push_back({to, [from = from](std::ostream& out) {
                       const std::string bytes = ReadTextFile(from);
                       out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
                     }});
  }
  WriteFilesAtomically(files);
}

namespace {

// Removes the folders <prefix><pid>_<n>@<host> in `parent` whose process on this host has ended
// (see ScratchDir). A name without "@<host>" (made before hosts were named) counts as this
// host's.
void RemoveScratchOfEndedRuns(const std::string& parent, const std::string& prefix,
                              const std::string& host) {
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(parent, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0 || !entry.is_directory(ec)) continue;
    const std::string rest = name.substr(prefix.size());
    const size_t digits = std::min(rest.find_first_not_of("0123456789"), rest.size());
    if (digits == 0 || digits > 9 || digits == rest.size() || rest[digits] != '_') continue;
    const size_t at = rest.find('@', digits);
    // The host name alone (the form before the PID namespace was part of the tag) counts too.
    if (at != std::string::npos && rest.substr(at + 1) != host &&
        rest.substr(at + 1) != HostName()) {
      continue;
    }
    const long pid = std::stol(rest.substr(0, digits));
    if (!ProcessEnded(pid)) continue;
    LOG(INFO) << "Removing " << entry.path().string() << ", left by a run (process " << pid
              << ") that was stopped";
    fs::remove_all(entry.path(), ec);
  }
}

}  // namespace

ScratchDir::ScratchDir(const std::string& parent, const std::string& prefix) {
  static std::atomic<int> counter{0};
  const std::string host = HostTag();
  RemoveScratchOfEndedRuns(parent, prefix, host);
  path_ = JoinPaths(parent, prefix + std::to_string(getpid()) + "_" +
                                std::to_string(counter++) + "@" + host);
  std::error_code ec;
  fs::remove_all(path_, ec);
  CreateDirs(path_);
}

ScratchDir::~ScratchDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

StagingDir::StagingDir(const std::string& parent, const std::string& name)
    : parent_(parent), scratch_(parent, "." + name + ".staging") {}

void StagingDir::Commit(const std::vector<std::string>& entries, bool replace) {
  THROW_IF(committed_, "StagingDir " << Path() << " was committed already");
  for (const std::string& entry : entries) {
    const std::string from = JoinPaths(Path(), entry);
    const std::string to = JoinPaths(parent_, entry);
    std::error_code ec;
    THROW_IF(!fs::exists(fs::symlink_status(from, ec)),
             "Cannot move " << from << " into place: it was not written");
    THROW_IF(!replace && fs::exists(fs::symlink_status(to, ec)),
             "Cannot move " << from << " to " << to << ": " << to
                            << " exists already (written by another process meanwhile?)");
  }
  for (const std::string& entry : entries) {
    const std::string from = JoinPaths(Path(), entry);
    const std::string to = JoinPaths(parent_, entry);
    if (replace) CreateDirs(ParentPath(to));
    std::error_code ec;
    fs::rename(from, to, ec);
    THROW_IF(ec, "Cannot rename " << from << " to " << to << ": " << ec.message());
  }
  committed_ = true;
}

void RemoveTemporaryFilesOnInterrupt() {
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction previous {};
    sigaction(signal_number, nullptr, &previous);
    // A signal the caller ignores (nohup's SIGHUP) stays ignored.
    if (previous.sa_handler == SIG_IGN) continue;
    struct sigaction action {};
    action.sa_handler = RemoveTemporariesAndDie;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND;
    sigaction(signal_number, &action, nullptr);
  }
  // A file past the size limit (ulimit -f) would otherwise end the process by SIGXFSZ with no
  // message and its temporary left; ignored, the write fails with EFBIG, which the writer
  // reports ("File too large") and cleans up after, as for a full disk.
  signal(SIGXFSZ, SIG_IGN);
}

}  // namespace hairmvs
