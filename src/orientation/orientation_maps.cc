#include "src/orientation/orientation_maps.h"

#include <zlib.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "colmap_ext/mat_io.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/option_parser.h"
#include "src/core/timer.h"
#include "src/orientation/orientation_field.h"

namespace hairmvs {
namespace {

constexpr char kNumLevelsOption[] = "OrientationField.num_levels";

// "<bytes> bytes, crc32 <hex>" of a file's bytes.
std::string FingerprintOf(const std::string& bytes) {
  // crc32_z takes a size_t length (crc32's uInt would need the file fed in pieces).
  const uLong crc = crc32_z(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(bytes.data()),
                            bytes.size());
  char hex[9];
  std::snprintf(hex, sizeof(hex), "%08lx", crc);
  return std::to_string(bytes.size()) + " bytes, crc32 " + hex;
}

std::string Fingerprint(const std::string& path) { return FingerprintOf(ReadTextFile(path)); }

// The provenance file is the inputs' provenance, then one line per level written with it,
// "level <k> <fingerprint>": so that levels another process replaced after this one wrote them
// (two runs with other options on one workspace) are not taken for this provenance's.
constexpr char kLevelPrefix[] = "level ";

std::string LevelLine(int level, const std::string& fingerprint) {
  return kLevelPrefix + std::to_string(level) + " " + fingerprint;
}

// Splits a provenance file into its inputs' lines and its level lines' fingerprints.
void SplitProvenanceFile(const std::string& text, std::string* inputs,
                         std::map<int, std::string>* level_fingerprints) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind(kLevelPrefix, 0) == 0) {
      std::istringstream fields(line.substr(sizeof(kLevelPrefix) - 1));
      int level = -1;
      std::string fingerprint;
      if (fields >> level && std::getline(fields >> std::ws, fingerprint)) {
        (*level_fingerprints)[level] = fingerprint;
      }
    } else {
      *inputs += line + "\n";
    }
  }
}

// Why the level at `path` is not the one its provenance recorded, or "" when it is.
std::string LevelChanged(const std::string& path, const std::string& recorded,
                         const std::string& actual) {
  if (recorded == actual) return "";
  return "its cached orientation fields changed after their provenance was written (" + path +
         " is " + actual + ", the provenance says " + recorded +
         "): another run wrote them meanwhile, or they were damaged";
}

}  // namespace

std::string OrientationFieldsProvenance(const Workspace& workspace, const std::string& name,
                                        int width, int height,
                                        const OrientationFieldOptions& options) {
  std::ostringstream out;
  out << "# hairmvs orientation fields of " << name
      << " (<name>.l<k>.bin beside this file): reused only while every line below holds\n";
  out << "image " << Fingerprint(workspace.ImagePath(name)) << "\n";
  const std::string mask_path = workspace.MaskPath(name);
  out << "mask " << (mask_path.empty() ? "none" : Fingerprint(mask_path)) << "\n";
  out << "size " << width << " x " << height << "\n";
  // The options as the commands print them (OptionParser::Values), one per line; one that the
  // fields do not depend on at its default, so that changing it keeps them.
  OrientationFieldOptions copy = options;
  if (copy.dark_strands) {  // SignedResponseRatio() does not read it then
    copy.min_positive_response_ratio = OrientationFieldOptions().min_positive_response_ratio;
  }
  OptionParser parser("orientation_fields", "");
  parser.AddSection("OrientationField", &copy);
  std::istringstream values(parser.Values());
  for (std::string line; std::getline(values, line);) {
    line = StripWhitespace(line);
    if (line.rfind(kNumLevelsOption, 0) != 0) out << line << "\n";
  }
  return out.str();
}

bool CachedOrientationFieldsHold(const Workspace& workspace, const std::string& name,
                                 const std::string& provenance, const StereoCamera& camera,
                                 int num_levels, std::string* why_not) {
  CHECK(why_not != nullptr);
  why_not->clear();
  const std::string provenance_path = workspace.OrientationMapProvenancePath(name);
  if (!ExistsFile(provenance_path)) {
    if (ExistsFile(workspace.OrientationMapPath(name, 0))) {
      *why_not = "its cached orientation fields have no " + provenance_path +
                 " (written by an older hairmvs, being written by another run, or their "
                 "writing was interrupted)";
    }
    return false;
  }
  std::string cached;
  std::map<int, std::string> level_fingerprints;
  SplitProvenanceFile(ReadTextFile(provenance_path), &cached, &level_fingerprints);
  if (cached != provenance) {
    std::istringstream was(cached), now(provenance);
    std::string was_line, now_line;
    while (true) {
      const bool more_was = static_cast<bool>(std::getline(was, was_line));
      const bool more_now = static_cast<bool>(std::getline(now, now_line));
      if (!more_was && !more_now) break;
      if (!more_was) was_line = "(nothing)";
      if (!more_now) now_line = "(nothing)";
      if (was_line != now_line) break;
    }
    *why_not = "its cached orientation fields were computed from other inputs (" +
               provenance_path + " says `" + was_line + "`, now `" + now_line + "`)";
    return false;
  }
  for (int l = 0; l < num_levels; ++l) {
    const std::string path = workspace.OrientationMapPath(name, l);
    if (!ExistsFile(path)) {
      *why_not = "its cached orientation fields stop before level " + std::to_string(l) +
                 " (no " + path + ")";
      return false;
    }
    MatShape shape;
    try {
      shape = ReadMatShape(path);  // the header and the file's size, not the payload
    } catch (const Error& e) {
      *why_not = std::string("its cached orientation fields cannot be read: ") + e.what();
      return false;
    }
    const StereoCamera level_camera = camera.PyramidLevel(l);
    const int width = level_camera.width, height = level_camera.height;
    if (shape.width != width || shape.height != height || shape.channels != 2) {
      std::ostringstream message;
      message << path << " is " << shape.width << " x " << shape.height << " x "
              << shape.channels << ", not the " << width << " x " << height
              << " x 2 of its level";
      *why_not = message.str();
      return false;
    }
    const auto recorded = level_fingerprints.find(l);
    if (recorded == level_fingerprints.end()) {
      *why_not = "its cached orientation fields' " + provenance_path + " records no level " +
                 std::to_string(l) + " (written by an older hairmvs)";
      return false;
    }
    // The size alone here (the payload is read only when the fields are), its crc32 on reading.
    const std::string recorded_bytes = recorded->second.substr(0, recorded->second.find(' '));
    const std::string actual_bytes = std::to_string(std::filesystem::file_size(path));
    if (recorded_bytes != actual_bytes) {
      *why_not = LevelChanged(path, recorded->second, actual_bytes + " bytes");
      return false;
    }
  }
  return true;
}

std::optional<std::vector<FloatMap>> ReadCachedOrientationFields(
    const Workspace& workspace, const std::string& name, const std::string& provenance,
    const StereoCamera& camera, int num_levels, std::string* why_not) {
  if (!CachedOrientationFieldsHold(workspace, name, provenance, camera, num_levels, why_not)) {
    return std::nullopt;
  }
  std::vector<FloatMap> levels;
  try {  // the files may change from the check on (another run writing them)
    std::string inputs;
    std::map<int, std::string> level_fingerprints;
    SplitProvenanceFile(ReadTextFile(workspace.OrientationMapProvenancePath(name)), &inputs,
                        &level_fingerprints);
    if (inputs != provenance) {
      *why_not = "its cached orientation fields' provenance changed while they were read";
      return std::nullopt;
    }
    for (int l = 0; l < num_levels; ++l) {
      const std::string path = workspace.OrientationMapPath(name, l);
      // The bytes read are those the provenance recorded: not another run's, written since.
      const std::string bytes = ReadTextFile(path);
      *why_not = LevelChanged(path, level_fingerprints[l], FingerprintOf(bytes));
      if (!why_not->empty()) return std::nullopt;
      std::istringstream in(bytes);
      levels.push_back(ReadMat(in, path));
    }
  } catch (const Error& e) {
    *why_not = std::string("its cached orientation fields cannot be read: ") + e.what();
    return std::nullopt;
  }
  return levels;
}

std::string OrientationPicturePath(const Workspace& workspace, const std::string& name,
                                   int level) {
  const std::string bin_path = workspace.OrientationMapPath(name, level);
  CHECK(bin_path.size() > 4 && bin_path.compare(bin_path.size() - 4, 4, ".bin") == 0);
  return bin_path.substr(0, bin_path.size() - 4) + ".png";
}

void WriteOrientationFields(const Workspace& workspace, const std::string& name,
                            const std::string& provenance, const std::vector<FloatMap>& levels) {
  const std::string provenance_path = workspace.OrientationMapProvenancePath(name);
  // What the fields these replace were, level by level: a level written again with the same
  // bytes (the stereo computing one more level than orientation_fields did) keeps its picture.
  std::map<int, std::string> old_fingerprints;
  if (ExistsFile(provenance_path)) {
    std::string old_inputs;
    SplitProvenanceFile(ReadTextFile(provenance_path), &old_inputs, &old_fingerprints);
  }
  std::error_code error;
  // Each level's fingerprint is of the bytes this run writes, not of the file after it (which
  // another run may have replaced already).
  std::vector<std::string> data(levels.size()), fingerprints(levels.size());
  for (size_t l = 0; l < levels.size(); ++l) {
    std::ostringstream bytes;
    WriteMat(bytes, levels[l]);
    data[l] = bytes.str();
    fingerprints[l] = FingerprintOf(data[l]);
  }
  // A picture of a level that changes, or is not written, would show other fields (and count as
  // up to date for a later --write_png 1): removed; the caller writes this run's, if asked.
  for (int l = 0; l < OrientationFieldOptions::kMaxLevels; ++l) {
    const bool same_bytes = l < static_cast<int>(levels.size()) && old_fingerprints.count(l) &&
                            old_fingerprints.at(l) == fingerprints[l];
    if (same_bytes) continue;
    const std::string picture = OrientationPicturePath(workspace, name, l);
    std::filesystem::remove(picture, error);
    THROW_IF(error, "Cannot remove " << picture << ": " << error.message());
  }
  // The levels and then their provenance as one unit, the provenance marking it whole: it is
  // removed before any level is replaced and written last, so that levels left half-replaced
  // by an interrupted run are never reused.
  std::string recorded = provenance;
  std::vector<FileToWrite> files;
  for (size_t l = 0; l < levels.size(); ++l) {
    files.push_back({workspace.OrientationMapPath(name, static_cast<int>(l)),
                     [&data, l](std::ostream& out) {
                       out.write(data[l].data(), static_cast<std::streamsize>(data[l].size()));
                     }});
    recorded += LevelLine(static_cast<int>(l), fingerprints[l]) + "\n";
  }
  files.push_back({provenance_path, [&recorded](std::ostream& out) { out << recorded; },
                   /*binary=*/false});
  WriteFilesAtomically(files, /*last_marks_complete=*/true);
  // Levels beyond these are of the fields replaced, which the provenance no longer lists.
  for (int l = static_cast<int>(levels.size()); l < OrientationFieldOptions::kMaxLevels; ++l) {
    const std::string stale = workspace.OrientationMapPath(name, l);
    std::filesystem::remove(stale, error);
    THROW_IF(error, "Cannot remove " << stale << ": " << error.message());
  }
}

std::vector<FloatMap> ComputeViewOrientationFields(const Workspace& workspace,
                                                   const std::string& name, int max_image_size,
                                                   OrientationFieldComputer* computer,
                                                   StageTimings* timings) {
  FloatMap gray, mask;
  {
    ScopedStageTimer timer(timings, "read image");
    gray = workspace.ReadViewGray(name, max_image_size);
    const std::string mask_path = workspace.MaskPath(name);
    if (!mask_path.empty()) mask = ReadMask(mask_path, gray.Width(), gray.Height());
  }
  return computer->Compute(gray, mask);
}

}  // namespace hairmvs
