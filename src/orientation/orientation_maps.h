#pragma once
// The orientation fields cached in stereo/orientation_maps/: `hairmvs orientation_fields` writes
// them and the stereo commands reuse them. Each view's levels (<name>.l<k>.bin) come with
// <name>.provenance.txt, which says what they were computed from: the image's and the mask's
// bytes (size and CRC-32), the size they were computed at and every filter option that shapes
// them. They are reused only while all of it still holds, so that a replaced image or mask, or
// another --OrientationField option, computes them again instead of silently reusing old ones.

#include <optional>
#include <string>
#include <vector>

#include "colmap_ext/workspace.h"
#include "hairmvs/orientation_fields.h"
#include "src/core/float_map.h"

namespace hairmvs {

// The picture of level `level` of `name`'s fields (`orientation_fields --write_png 1`):
// <name>.l<k>.png beside the level's Mat.
std::string OrientationPicturePath(const Workspace& workspace, const std::string& name,
                                   int level);

// The provenance of the fields of image `name` computed at width x height with `options`,
// as the text of its provenance file. OrientationField.num_levels is left out: level k does
// not depend on how many levels are computed. Throws naming the file if the image or its
// mask cannot be read.
std::string OrientationFieldsProvenance(const Workspace& workspace, const std::string& name,
                                        int width, int height,
                                        const OrientationFieldOptions& options);

// Whether the cached levels [0, num_levels) of `name` are those of `provenance` for `camera`
// (its size, and its PyramidLevel(k)'s for level k): its provenance file equals `provenance` and
// every level is there, 2-channel and of its size (the headers and file sizes are read, not
// the payloads). If not, `*why_not` says what differs (the first line of the provenance that
// does not hold) or what is missing; it is left empty when nothing of `name` is cached at all.
bool CachedOrientationFieldsHold(const Workspace& workspace, const std::string& name,
                                 const std::string& provenance, const StereoCamera& camera,
                                 int num_levels, std::string* why_not);
// The cached levels, where CachedOrientationFieldsHold and each level's bytes are those its
// provenance recorded (their crc32); otherwise nullopt and `*why_not` says what differs.
std::optional<std::vector<FloatMap>> ReadCachedOrientationFields(
    const Workspace& workspace, const std::string& name, const std::string& provenance,
    const StereoCamera& camera, int num_levels, std::string* why_not);

class OrientationFieldComputer;  // src/orientation/orientation_field.h
class StageTimings;              // src/core/timer.h

// The fields of `name` that the cache does not hold, computed by `computer` (its options'
// levels) from the image read at `max_image_size` and the view's mask (none where it has none):
// the one way `hairmvs orientation_fields` and the stereo compute them, so that either's
// fields are the other's to reuse. The image and mask are read under the stage "read image"
// of `timings` (null: not timed apart).
std::vector<FloatMap> ComputeViewOrientationFields(const Workspace& workspace,
                                                   const std::string& name, int max_image_size,
                                                   OrientationFieldComputer* computer,
                                                   StageTimings* timings = nullptr);

// Writes the levels of `name`, then its provenance, as one unit (WriteFilesAtomically with the
// provenance marking it whole): the old provenance is removed before any level is replaced, so
// that levels left half-replaced by an interrupted run are never reused.
void WriteOrientationFields(const Workspace& workspace, const std::string& name,
                            const std::string& provenance, const std::vector<FloatMap>& levels);

}  // namespace hairmvs
