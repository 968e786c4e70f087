#include "colmap_ext/source_views.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace hairmvs {

namespace {

constexpr double kPi = 3.14159265358979323846;

double RadToDeg(double rad) { return rad * 180.0 / kPi; }
double DegToRad(double deg) { return deg * kPi / 180.0; }

// COLMAP's CalculateTriangulationAngle: the angle between the two rays, folded to [0, pi/2].
double TriangulationAngleRad(const Eigen::Vector3d& centre1, const Eigen::Vector3d& centre2,
                             const Eigen::Vector3d& point) {
  const double baseline2 = (centre1 - centre2).squaredNorm();
  const double ray1 = (point - centre1).norm();
  const double ray2 = (point - centre2).norm();
  const double denominator = 2.0 * ray1 * ray2;
  if (denominator == 0.0) return 0.0;
  const double nominator = ray1 * ray1 + ray2 * ray2 - baseline2;
  const double angle = std::abs(std::acos(std::clamp(nominator / denominator, -1.0, 1.0)));
  return std::min(angle, kPi - angle);
}

// COLMAP's Percentile: element round(p/100 * (n-1)) of the sorted values, no interpolation.
double Percentile(std::vector<double> values, double percent) {
  CHECK(!values.empty());
  const size_t index = static_cast<size_t>(
      std::lround(percent / 100.0 * static_cast<double>(values.size() - 1)));
  std::nth_element(values.begin(), values.begin() + index, values.end());
  return values[index];
}

// Smallest difference of two angles modulo pi, in [0, pi/2].
double AngleDistanceModPi(double a, double b) {
  double d = std::fmod(std::abs(a - b), kPi);
  return std::min(d, kPi - d);
}

struct PairStats {
  int shared_points = 0;
  std::vector<double> angles_rad;
};

// For every reference image id: the other images sharing sparse points with it.
std::map<uint32_t, std::map<uint32_t, PairStats>> ComputePairStats(const Reconstruction& model) {
  std::map<uint32_t, Eigen::Vector3d> centres;
  for (const auto& [id, image] : model.images) centres[id] = image.ProjectionCenter();
  std::map<uint32_t, std::map<uint32_t, PairStats>> stats;
  for (const auto& [point_id, point] : model.points3D) {
    std::vector<uint32_t> ids;
    for (const TrackElement& el : point.track) {
      if (centres.count(el.image_id)) ids.push_back(el.image_id);
    }
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    for (size_t i = 0; i < ids.size(); ++i) {
      for (size_t j = i + 1; j < ids.size(); ++j) {
        const double angle =
            TriangulationAngleRad(centres[ids[i]], centres[ids[j]], point.xyz);
        for (const auto& [a, b] : {std::pair(ids[i], ids[j]), std::pair(ids[j], ids[i])}) {
          PairStats& s = stats[a][b];
          ++s.shared_points;
          s.angles_rad.push_back(angle);
        }
      }
    }
  }
  return stats;
}

struct Candidate {
  uint32_t image_id = 0;
  std::string name;
  int shared_points = 0;
  double angle75_rad = 0;
  double epipolar_rad = 0;
  Eigen::Vector2d baseline_in_image = Eigen::Vector2d::Zero();  // reference camera x, y
  double baseline_z_m = 0;  // along the reference's optical axis
  double baseline_m = 0;
  double view_angle_rad = 0;  // between the two optical axes
};

Eigen::Vector2d ImageCentre(const Reconstruction& model, const Image& image) {
  const Camera& camera = model.cameras.at(image.camera_id);
  return Eigen::Vector2d(camera.width / 2.0, camera.height / 2.0);
}

std::string FormatDeg(double rad) {
  std::ostringstream ss;
  // Rounded to whole degrees, modulo 180 (179.6 prints as 0).
  ss << std::fmod(std::round(RadToDeg(rad)), 180.0);
  return ss.str();
}

// Gantry T group among `candidates`: the nearest views whose epipolar lines at the reference
// centre are horizontal (one baseline to the left, one to the right) and vertical, with
// baselines mostly parallel to the image plane, similar viewing directions and similar
// lengths. Returns the indices (left, right, vertical) or nothing.
std::vector<size_t> FindTGroup(const std::vector<Candidate>& candidates,
                               const SourceViewOptions& options) {
  const double max_axis = DegToRad(options.t_group_max_axis_angle_deg);
  const double max_view = DegToRad(options.t_group_max_view_angle_deg);
  int best[3] = {-1, -1, -1};  // left, right, vertical
  for (size_t i = 0; i < candidates.size(); ++i) {
    const Candidate& c = candidates[i];
    const Eigen::Vector2d& b = c.baseline_in_image;
    if (b.norm() < 1e-12 || std::abs(c.baseline_z_m) > 0.5 * b.norm()) continue;
    if (c.view_angle_rad > max_view) continue;
    const double from_horizontal = AngleDistanceModPi(c.epipolar_rad, 0.0);
    int slot = -1;
    if (from_horizontal <= max_axis) {
      slot = b.x() < 0 ? 0 : 1;
    } else if (kPi / 2 - from_horizontal <= max_axis) {
      slot = 2;
    }
    if (slot < 0) continue;
    if (best[slot] < 0 || c.baseline_m < candidates[best[slot]].baseline_m) {
      best[slot] = static_cast<int>(i);
    }
  }
  if (best[0] < 0 || best[1] < 0 || best[2] < 0) return {};
  double lo = 1e300, hi = 0;
  for (int slot : best) {
    lo = std::min(lo, candidates[slot].baseline_m);
    hi = std::max(hi, candidates[slot].baseline_m);
  }
  if (!(lo > 0) || hi / lo > options.t_group_max_distance_ratio) return {};
  return {static_cast<size_t>(best[0]), static_cast<size_t>(best[1]),
          static_cast<size_t>(best[2])};
}

SourceViewSelection SelectAuto(const Workspace& ws, const Image& reference,
                               const std::map<uint32_t, PairStats>& pairs, int num_sources,
                               const SourceViewOptions& options, const std::string& origin) {
  const Reconstruction& model = ws.Model();
  SourceViewSelection selection;
  selection.reference = reference.name;
  const Eigen::Vector2d centre_px = ImageCentre(model, reference);
  const double min_angle = DegToRad(options.min_triangulation_angle_deg);
  std::vector<Candidate> candidates;
  int num_sharing = 0;
  for (const auto& [other_id, stats] : pairs) {
    const Image& other = model.images.at(other_id);
    if (!ws.HasImageFile(other.name)) continue;  // not in images/: no view
    ++num_sharing;
    const double angle75 = Percentile(stats.angles_rad, 75.0);
    if (angle75 < min_angle) continue;
    Candidate c;
    c.image_id = other_id;
    c.name = other.name;
    c.shared_points = stats.shared_points;
    c.angle75_rad = angle75;
    c.epipolar_rad = EpipolarDirectionRad(model, reference.image_id, other_id, centre_px);
    const Eigen::Vector3d baseline =
        reference.R() * (other.ProjectionCenter() - reference.ProjectionCenter());
    c.baseline_in_image = baseline.head<2>();
    c.baseline_z_m = baseline.z();
    c.baseline_m = baseline.norm();
    c.view_angle_rad = std::acos(std::clamp(
        reference.ViewingDirection().dot(other.ViewingDirection()), -1.0, 1.0));
    candidates.push_back(c);
  }
  // Deterministic order before the greedy choice: more shared points first, then image id.
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return a.shared_points != b.shared_points ? a.shared_points > b.shared_points
                                              : a.image_id < b.image_id;
  });

  std::vector<size_t> chosen;
  const std::vector<size_t> t_group = FindTGroup(candidates, options);
  if (t_group.size() == 3 && num_sources >= 3) {
    chosen = t_group;
    selection.gantry_t_group = true;
  }
  // Very wide baselines (75th-percentile angle above max_triangulation_angle_deg) change the
  // hair's appearance too much for orientation matching: used only when nothing else is left.
  const double max_angle = DegToRad(options.max_triangulation_angle_deg);
  int num_wide = 0;
  for (const Candidate& c : candidates) num_wide += c.angle75_rad > max_angle;
  int max_shared = 1;
  for (const Candidate& c : candidates) max_shared = std::max(max_shared, c.shared_points);
  while (static_cast<int>(chosen.size()) < num_sources && chosen.size() < candidates.size()) {
    // Wide ones only when no narrow one is left unchosen (the T group may hold wide ones).
    bool allow_wide = true;
    for (size_t i = 0; i < candidates.size() && allow_wide; ++i) {
      allow_wide = candidates[i].angle75_rad > max_angle ||
                   std::find(chosen.begin(), chosen.end(), i) != chosen.end();
    }
    double best_score = -1;
    size_t best = 0;
    for (size_t i = 0; i < candidates.size(); ++i) {
      if (std::find(chosen.begin(), chosen.end(), i) != chosen.end()) continue;
      if (!allow_wide && candidates[i].angle75_rad > max_angle) continue;
      double spread = 1.0;
      for (size_t j : chosen) {
        spread = std::min(spread, AngleDistanceModPi(candidates[i].epipolar_rad,
                                                     candidates[j].epipolar_rad) /
                                      (kPi / 2));
      }
      const double score = static_cast<double>(candidates[i].shared_points) / max_shared *
                           (1.0 + options.epipolar_spread_weight * spread);
      if (score > best_score) {
        best_score = score;
        best = i;
      }
    }
    chosen.push_back(best);
  }

  for (size_t i : chosen) {
    selection.sources.push_back(candidates[i].name);
    selection.shared_points.push_back(candidates[i].shared_points);
    selection.triangulation_angle_deg.push_back(RadToDeg(candidates[i].angle75_rad));
    selection.epipolar_direction_deg.push_back(RadToDeg(candidates[i].epipolar_rad));
  }
  std::ostringstream reason;
  reason << origin << ": " << candidates.size() << " of " << num_sharing
         << " views sharing points pass the " << options.min_triangulation_angle_deg
         << " deg test";
  if (num_wide > 0) {
    reason << " (" << num_wide << " wider than " << options.max_triangulation_angle_deg
           << " deg, used last)";
  }
  if (selection.gantry_t_group) {
    reason << "; gantry T group (left " << candidates[t_group[0]].name << ", right "
           << candidates[t_group[1]].name << ", vertical " << candidates[t_group[2]].name
           << ", baselines " << std::fixed << std::setprecision(3)
           << candidates[t_group[0]].baseline_m << "/" << candidates[t_group[1]].baseline_m
           << "/" << candidates[t_group[2]].baseline_m << " m) chosen first";
    reason.unsetf(std::ios::fixed);
  }
  if (!chosen.empty()) {
    reason << "; ranked by shared points x epipolar spread (weight "
           << options.epipolar_spread_weight << "), epipolar directions";
    for (size_t i : chosen) reason << " " << FormatDeg(candidates[i].epipolar_rad);
    reason << " deg mod 180";
  }
  selection.reason = reason.str();
  return selection;
}

void FillExplicitStats(const Workspace& ws, const Image& reference,
                       const std::map<uint32_t, PairStats>& pairs,
                       SourceViewSelection* selection) {
  const Reconstruction& model = ws.Model();
  const Eigen::Vector2d centre_px = ImageCentre(model, reference);
  for (const std::string& name : selection->sources) {
    const Image& other = model.ImageByName(name);
    const auto it = pairs.find(other.image_id);
    selection->shared_points.push_back(it == pairs.end() ? 0 : it->second.shared_points);
    selection->triangulation_angle_deg.push_back(
        it == pairs.end() ? 0.0 : RadToDeg(Percentile(it->second.angles_rad, 75.0)));
    selection->epipolar_direction_deg.push_back(RadToDeg(
        EpipolarDirectionRad(model, reference.image_id, other.image_id, centre_px)));
  }
}

// Keeps the `max_sources` sources sharing the most sparse points with the reference (ties: the
// listed order), with their statistics, and says so in the reason.
void KeepSourcesSharingMostPoints(int max_sources, SourceViewSelection* selection) {
  const size_t num_listed = selection->sources.size();
  std::vector<size_t> order(num_listed);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return selection->shared_points[a] > selection->shared_points[b];
  });
  order.resize(max_sources);
  SourceViewSelection kept;
  kept.reference = selection->reference;
  kept.gantry_t_group = selection->gantry_t_group;
  for (size_t i : order) {
    kept.sources.push_back(selection->sources[i]);
    kept.shared_points.push_back(selection->shared_points[i]);
    kept.triangulation_angle_deg.push_back(selection->triangulation_angle_deg[i]);
    kept.epipolar_direction_deg.push_back(selection->epipolar_direction_deg[i]);
  }
  std::ostringstream reason;
  reason << selection->reason << "; the " << max_sources << " of " << num_listed
         << " sharing the most sparse points kept (max_num_source_views)";
  kept.reason = reason.str();
  *selection = std::move(kept);
}

}  // namespace

bool SourceViewOptions::Check(std::string* error) const {
  std::ostringstream e;
  if (max_num_source_views < 1) e << "max_num_source_views must be >= 1. ";
  if (!(min_triangulation_angle_deg >= 0 && min_triangulation_angle_deg < 90)) {
    e << "min_triangulation_angle_deg must be in [0, 90). ";
  }
  if (!(epipolar_spread_weight >= 0)) e << "epipolar_spread_weight must be >= 0. ";
  if (!(max_triangulation_angle_deg > min_triangulation_angle_deg)) {
    e << "max_triangulation_angle_deg must exceed min_triangulation_angle_deg. ";
  } else if (!(max_triangulation_angle_deg <= 180)) {
    e << "max_triangulation_angle_deg must be at most 180. ";
  }
  if (!(t_group_max_view_angle_deg > 0 && t_group_max_view_angle_deg <= 180)) {
    e << "t_group_max_view_angle_deg must be in (0, 180]. ";
  }
  if (!(t_group_max_axis_angle_deg > 0 && t_group_max_axis_angle_deg < 45)) {
    e << "t_group_max_axis_angle_deg must be in (0, 45). ";
  }
  if (!(t_group_max_distance_ratio >= 1)) e << "t_group_max_distance_ratio must be >= 1. ";
  if (error != nullptr) *error = StripWhitespace(e.str());
  return e.str().empty();
}

double EpipolarDirectionRad(const Reconstruction& model, uint32_t reference_id,
                            uint32_t source_id, const Eigen::Vector2d& point_px) {
  const Image& reference = model.images.at(reference_id);
  const Image& source = model.images.at(source_id);
  const Eigen::Matrix3d K = model.cameras.at(reference.camera_id).CalibrationMatrix();
  // The epipole e = K (R C_src + t) in homogeneous image coordinates; the line through the
  // point x and e has direction e_xy - e_z * x, which stays valid when e is at infinity.
  const Eigen::Vector3d e = K * (reference.R() * source.ProjectionCenter() + reference.t());
  Eigen::Vector2d d = e.head<2>() - e.z() * point_px;
  if (d.norm() < 1e-12) return 0.0;
  double angle = std::atan2(d.y(), d.x());
  if (angle < 0) angle += kPi;
  if (angle >= kPi) angle -= kPi;
  return angle;
}

std::vector<SourceViewSelection> SelectSourceViews(const Workspace& ws,
                                                   const SourceViewOptions& options) {
  std::string error;
  THROW_IF(!options.Check(&error), "Invalid source view options: " << error);
  // The epipolar directions need every camera's K: a distorted one is named with its folder.
  ws.RequireUndistortedCameras();
  const Reconstruction& model = ws.Model();
  const std::string cfg_path = options.config_path.empty()
                                   ? JoinPaths(ws.StereoPath(), "patch-match.cfg")
                                   : options.config_path;
  if (!options.config_path.empty()) RequireFile(cfg_path, "patch-match config (config_path)");
  std::vector<PatchMatchProblem> problems;
  std::string origin_prefix;
  // A folder in its place is an error (ReadPatchMatchConfig's), not a missing file.
  if (options.use_config && Exists(cfg_path)) {
    problems = ReadPatchMatchConfig(cfg_path, model);
    origin_prefix = std::filesystem::path(cfg_path).filename().string();
  } else {
    for (const std::string& name : ws.ImageNames()) {
      PatchMatchProblem p;
      p.reference = name;
      p.kind = PatchMatchProblem::Kind::kAuto;
      p.num_auto = options.max_num_source_views;
      problems.push_back(p);
    }
  }
  const auto pair_stats = ComputePairStats(model);
  static const std::map<uint32_t, PairStats> kNoPairs;
  std::vector<SourceViewSelection> selections;
  int num_capped = 0;  // references whose list was longer than max_num_source_views
  for (const PatchMatchProblem& problem : problems) {
    const Image& reference = model.ImageByName(problem.reference);
    const auto it = pair_stats.find(reference.image_id);
    const std::map<uint32_t, PairStats>& pairs = it == pair_stats.end() ? kNoPairs : it->second;
    SourceViewSelection selection;
    std::ostringstream where;
    if (!origin_prefix.empty()) where << origin_prefix << ":" << problem.line_number << " ";
    const std::string listed_by = origin_prefix.empty()
                                      ? std::string()
                                      : cfg_path + ":" + std::to_string(problem.line_number);
    ws.RequireView(problem.reference, listed_by);
    if (problem.kind == PatchMatchProblem::Kind::kExplicit) {
      for (const std::string& source : problem.sources) ws.RequireView(source, listed_by);
    }
    switch (problem.kind) {
      case PatchMatchProblem::Kind::kExplicit:
        selection.reference = problem.reference;
        selection.sources = problem.sources;
        selection.reason = where.str() + "explicit list";
        FillExplicitStats(ws, reference, pairs, &selection);
        break;
      case PatchMatchProblem::Kind::kAll:
        selection.reference = problem.reference;
        for (const std::string& name : ws.ImageNames()) {
          if (name != problem.reference) selection.sources.push_back(name);
        }
        selection.reason = where.str() + "__all__";
        FillExplicitStats(ws, reference, pairs, &selection);
        break;
      case PatchMatchProblem::Kind::kAuto: {
        const int n = std::min(problem.num_auto, options.max_num_source_views);
        std::ostringstream origin;
        if (origin_prefix.empty()) {
          origin << "auto (no patch-match.cfg), " << n;
        } else {
          origin << where.str() << "__auto__, " << problem.num_auto;
          if (n < problem.num_auto) origin << " capped to max_num_source_views " << n;
        }
        selection = SelectAuto(ws, reference, pairs, n, options, origin.str());
        break;
      }
    }
    // One cap for every kind: the estimate loads every source's fields and the geometric pass
    // reads every source's map (COLMAP takes whole lists, and samples among them per pixel).
    if (static_cast<int>(selection.sources.size()) > options.max_num_source_views) {
      KeepSourcesSharingMostPoints(options.max_num_source_views, &selection);
      ++num_capped;
    }
    // COLMAP drops references without sources (with a warning).
    if (selection.sources.empty()) {
      LOG(WARNING) << "Ignoring reference image " << problem.reference
                   << ": no source images (" << selection.reason << ")";
      continue;
    }
    selections.push_back(std::move(selection));
  }
  if (num_capped > 0) {
    LOG(WARNING) << cfg_path << ": " << num_capped << " reference(s) list more than "
                 << options.max_num_source_views << " sources (explicitly or with __all__); "
                 << "each keeps the " << options.max_num_source_views << " sharing the most "
                 << "sparse points with it (--SourceViews.max_num_source_views keeps more; "
                 << "hairmvs workspace_info lists them)";
  }
  return selections;
}

// ---------------------------------------------------------------------------------------------
// Depth ranges.

namespace {

// COLMAP's percentile rule on the depths of the points that `keep` accepts.
template <typename KeepFn>
DepthRange DepthRangeOfPoints(const Reconstruction& model, uint32_t image_id, KeepFn keep) {
  const Image& image = model.images.at(image_id);
  const Eigen::Matrix3d R = image.R();
  std::vector<double> depths;
  for (const auto& [point_id, point] : model.points3D) {
    for (const TrackElement& el : point.track) {
      if (el.image_id != image_id || !keep(el)) continue;
      const double d = R.row(2).dot(point.xyz) + image.t().z();
      if (d > 0) depths.push_back(d);
    }
  }
  DepthRange range;
  range.num_points = static_cast<int>(depths.size());
  if (depths.empty()) return range;
  std::sort(depths.begin(), depths.end());
  const size_t n = depths.size();
  range.min_m = 0.75 * depths[static_cast<size_t>(0.01 * n)];
  range.max_m = 1.25 * depths[std::min(n - 1, static_cast<size_t>(0.99 * n))];
  return range;
}

}  // namespace

DepthRange ComputeDepthRange(const Reconstruction& model, uint32_t image_id) {
  return DepthRangeOfPoints(model, image_id, [](const TrackElement&) { return true; });
}

DepthRange ComputeDepthRange(const Reconstruction& model, uint32_t image_id,
                             const FloatMap& mask, int min_points) {
  const Image& image = model.images.at(image_id);
  const Camera& camera = model.cameras.at(image.camera_id);
  const double sx = static_cast<double>(mask.Width()) / camera.width;
  const double sy = static_cast<double>(mask.Height()) / camera.height;
  const DepthRange masked = DepthRangeOfPoints(model, image_id, [&](const TrackElement& el) {
    if (el.point2D_idx >= image.points2D.size()) return false;
    const Eigen::Vector2d& xy = image.points2D[el.point2D_idx].xy;
    const int col = static_cast<int>(std::floor(xy.x() * sx));
    const int row = static_cast<int>(std::floor(xy.y() * sy));
    return col >= 0 && row >= 0 && col < mask.Width() && row < mask.Height() &&
           mask.At(row, col) > 0.0f;
  });
  if (masked.num_points >= min_points) {
    DepthRange range = masked;
    range.inside_mask = true;
    return range;
  }
  return ComputeDepthRange(model, image_id);
}

std::vector<std::string> NearestInDirection(const Workspace& ws, const std::string& reference,
                                            const std::vector<std::string>& candidates,
                                            size_t max_num_views) {
  if (candidates.size() <= max_num_views) return candidates;
  const Eigen::Vector3d direction = ws.ImageByName(reference).ViewingDirection();
  std::vector<std::pair<double, size_t>> by_cosine;  // -cos: the nearest sort first
  for (size_t i = 0; i < candidates.size(); ++i) {
    by_cosine.emplace_back(-direction.dot(ws.ImageByName(candidates[i]).ViewingDirection()), i);
  }
  std::sort(by_cosine.begin(), by_cosine.end());
  std::vector<size_t> kept;
  for (size_t k = 0; k < max_num_views; ++k) kept.push_back(by_cosine[k].second);
  std::sort(kept.begin(), kept.end());
  std::vector<std::string> nearest;
  for (size_t i : kept) nearest.push_back(candidates[i]);
  return nearest;
}

std::vector<std::string> ViewsLookingTheSameWay(const Workspace& ws, const std::string& reference,
                                                const std::vector<std::string>& exclude,
                                                double max_view_angle_deg) {
  const Eigen::Vector3d direction = ws.ImageByName(reference).ViewingDirection();
  const double min_cos = std::cos(max_view_angle_deg * kPi / 180.0);
  std::vector<std::string> views;
  for (const std::string& name : ws.ImageNames()) {
    if (name == reference || std::find(exclude.begin(), exclude.end(), name) != exclude.end()) {
      continue;
    }
    if (direction.dot(ws.ImageByName(name).ViewingDirection()) >= min_cos) views.push_back(name);
  }
  return views;
}

// ---------------------------------------------------------------------------------------------
// Config files.

std::vector<PatchMatchProblem> ReadPatchMatchConfig(const std::string& path,
                                                    const Reconstruction& model) {
  RequireFile(path, "patch-match config");
  const std::vector<std::string> lines = ReadLines(path);
  std::vector<PatchMatchProblem> problems;
  auto require_image = [&](const std::string& name, size_t line_index) {
    THROW_IF(name.empty(), path << ":" << line_index + 1 << ": empty image name");
    THROW_IF(model.FindImageByName(name) == nullptr,
             path << ":" << line_index + 1 << ": Image with name `" << name
                  << "` does not exist in the sparse model");
  };
  bool have_reference = false;
  PatchMatchProblem problem;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string line = StripWhitespace(lines[i]);
    if (line.empty() || line[0] == '#') continue;
    if (!have_reference) {
      require_image(line, i);
      problem = PatchMatchProblem();
      problem.reference = line;
      have_reference = true;
      continue;
    }
    problem.line_number = static_cast<int>(i + 1);
    // As COLMAP's CSVToVector: tokens trimmed, empty ones skipped (`a.png, b.png,` is two
    // sources; a line of separators alone lists none, and the reference is dropped).
    std::vector<std::string> tokens;
    for (const std::string& part : SplitString(line, ",;")) {
      std::string token = StripWhitespace(part);
      if (!token.empty()) tokens.push_back(std::move(token));
    }
    if (tokens.empty()) {
      problem.kind = PatchMatchProblem::Kind::kExplicit;
    } else if (tokens[0] == "__all__") {
      THROW_IF(tokens.size() != 1, path << ":" << i + 1 << ": `__all__` takes no arguments");
      problem.kind = PatchMatchProblem::Kind::kAll;
    } else if (tokens[0] == "__auto__") {
      THROW_IF(tokens.size() != 2,
               path << ":" << i + 1 << ": expected `__auto__, N` (exactly two tokens), found '"
                    << line << "'");
      int n = 0;
      std::istringstream ss(tokens[1]);
      THROW_IF(!(ss >> n) || !ss.eof() || n <= 0,
               path << ":" << i + 1 << ": `__auto__, N` needs a positive integer N, found '"
                    << tokens[1] << "'");
      problem.kind = PatchMatchProblem::Kind::kAuto;
      problem.num_auto = n;
    } else {
      problem.kind = PatchMatchProblem::Kind::kExplicit;
      for (const std::string& name : tokens) {
        require_image(name, i);
        THROW_IF(name == problem.reference,
                 path << ":" << i + 1 << ": reference " << name << " lists itself as a source");
        // Twice, a source would count as two views in the data term and the consistency test.
        THROW_IF(std::find(problem.sources.begin(), problem.sources.end(), name) !=
                     problem.sources.end(),
                 path << ":" << i + 1 << ": source " << name << " is listed twice");
        problem.sources.push_back(name);
      }
    }
    problems.push_back(problem);
    have_reference = false;
  }
  THROW_IF(have_reference, path << ": reference " << problem.reference
                                << " has no sources line (lines come in pairs: reference, "
                                   "then sources / __auto__, N / __all__)");
  return problems;
}

std::vector<std::string> ReadFusionConfig(const std::string& path, const Reconstruction& model) {
  RequireFile(path, "fusion config");
  const std::vector<std::string> lines = ReadLines(path);
  std::vector<std::string> names;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string name = StripWhitespace(lines[i]);
    if (name.empty()) continue;
    THROW_IF(name[0] == '#', path << ":" << i + 1
                                  << ": comment line; fusion.cfg lists one image name per line "
                                     "and COLMAP aborts on `#` lines there");
    THROW_IF(model.FindImageByName(name) == nullptr,
             path << ":" << i + 1 << ": Image with name `" << name
                  << "` does not exist in the sparse model");
    names.push_back(name);
  }
  return names;
}

void WritePatchMatchConfig(const std::string& path,
                           const std::vector<PatchMatchProblem>& problems) {
  WriteFileAtomically(
      path,
      [&](std::ostream& out) {
        for (const PatchMatchProblem& p : problems) {
          out << p.reference << "\n";
          switch (p.kind) {
            case PatchMatchProblem::Kind::kAll: out << "__all__\n"; break;
            case PatchMatchProblem::Kind::kAuto: out << "__auto__, " << p.num_auto << "\n"; break;
            case PatchMatchProblem::Kind::kExplicit:
              CHECK(!p.sources.empty()) << p.reference;
              out << JoinStrings(p.sources, ", ") << "\n";
              break;
          }
        }
      },
      false);
}

void WriteFusionConfig(const std::string& path, const std::vector<std::string>& image_names) {
  WriteFileAtomically(
      path,
      [&](std::ostream& out) {
        for (const std::string& name : image_names) out << name << "\n";
      },
      false);
}

}  // namespace hairmvs
