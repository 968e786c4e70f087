#include "colmap_ext/workspace_info.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/core/timer.h"

namespace hairmvs {

WorkspaceInfo ComputeWorkspaceInfo(const std::string& workspace_path,
                                   const std::string& mask_path,
                                   const SourceViewOptions& options) {
  Timer timer;
  WorkspaceInfo info;
  info.workspace_path = workspace_path;
  const Workspace ws = Workspace::Read(workspace_path, mask_path);
  const Reconstruction& model = ws.Model();
  info.num_cameras = static_cast<int>(model.cameras.size());
  info.num_points3D = static_cast<int>(model.points3D.size());
  for (const auto& [id, camera] : model.cameras) {
    std::ostringstream line;
    line << "camera " << id << ": " << camera.ModelName() << " " << camera.width << "x"
         << camera.height;
    if (camera.IsPinhole()) {
      const Eigen::Matrix3d K = camera.CalibrationMatrix();
      line << std::setprecision(6) << "  K: fx " << K(0, 0) << " fy " << K(1, 1) << " cx "
           << K(0, 2) << " cy " << K(1, 2);
    } else {
      line << "  params:";
      for (double p : camera.params) line << " " << p;
      line << "  (not undistorted: run colmap image_undistorter)";
    }
    info.camera_lines.push_back(line.str());
  }
  for (const std::string& name : ws.ImageNames()) {
    const Image& image = ws.ImageByName(name);
    WorkspaceInfoViewRow row;
    row.name = name;
    row.image_idx = ws.ImageIdx(name);
    row.image_id = image.image_id;
    row.camera_id = image.camera_id;
    row.num_points2D = static_cast<int>(image.points2D.size());
    for (const Point2D& p : image.points2D) {
      row.num_points3D += p.point3D_id != kInvalidPoint3DId && model.points3D.count(p.point3D_id);
    }
    // Read as the stereo reads it (decoded whole: a file cut short or of another size than its
    // camera is found here, not minutes into a run).
    try {
      ws.ReadViewGray(name);
    } catch (const Error& e) {
      row.image_error = e.what();
    }
    row.mask_path = ws.MaskPath(name);
    if (!row.mask_path.empty()) {
      const Camera& camera = model.cameras.at(image.camera_id);
      // A report lists an unusable mask (the stereo stops on it) rather than stopping itself.
      try {
        const FloatMap mask = ReadMask(row.mask_path, static_cast<int>(camera.width),
                                       static_cast<int>(camera.height));
        double kept = 0;
        for (float v : mask.Data()) kept += v;
        row.mask_keep_fraction = kept / static_cast<double>(mask.NumPixels());
      } catch (const Error& e) {
        row.mask_error = e.what();
      }
    }
    row.depth_range = ComputeDepthRange(model, image.image_id);
    info.views.push_back(row);
  }
  info.selections = SelectSourceViews(ws, options);
  for (const SourceViewSelection& s : info.selections) info.num_t_groups += s.gantry_t_group;
  info.seconds = timer.ElapsedSeconds();
  return info;
}

std::string WorkspaceInfo::Report() const {
  std::ostringstream out;
  int num_masks = 0;
  for (const WorkspaceInfoViewRow& v : views) num_masks += !v.mask_path.empty();
  out << "Workspace " << workspace_path << ": " << views.size() << " views, " << num_cameras
      << " cameras, " << num_points3D << " sparse points, " << num_masks << " masks\n";
  out << "Cameras:\n";
  for (const std::string& line : camera_lines) out << "  " << line << "\n";
  out << "Views (image_idx name id camera points2D/with3D mask-keep depth-range[m] from n):\n";
  for (const WorkspaceInfoViewRow& v : views) {
    out << "  " << std::setw(3) << v.image_idx << " " << v.name << " id " << v.image_id
        << " cam " << v.camera_id << " " << v.num_points2D << "/" << v.num_points3D << " ";
    if (!v.image_error.empty()) out << "image UNUSABLE ";
    if (v.mask_path.empty()) {
      out << "no-mask";
    } else if (!v.mask_error.empty()) {
      out << "mask UNUSABLE";
    } else {
      out << "mask " << std::fixed << std::setprecision(3) << v.mask_keep_fraction;
    }
    out << std::fixed << std::setprecision(4);
    if (v.depth_range.min_m > 0) {
      out << " depth " << v.depth_range.min_m << "-" << v.depth_range.max_m << " from "
          << v.depth_range.num_points;
    } else {
      out << " depth none (no sparse points: give the stereo --OrientationStereo.depth_min and "
             "depth_max)";
    }
    out.unsetf(std::ios::fixed);
    out << std::setprecision(6) << "\n";
  }
  for (const WorkspaceInfoViewRow& v : views) {
    if (!v.image_error.empty()) out << "Unusable image: " << v.image_error << "\n";
    if (!v.mask_error.empty()) out << "Unusable mask: " << v.mask_error << "\n";
  }
  out << "Source views (" << selections.size() << " references, " << num_t_groups
      << " gantry T groups):\n";
  for (const SourceViewSelection& s : selections) {
    out << "  " << s.reference << " <-";
    for (size_t k = 0; k < s.sources.size(); ++k) {
      out << " " << s.sources[k];
      if (k < s.shared_points.size()) {
        out << " (" << s.shared_points[k] << " pts, " << std::fixed << std::setprecision(1)
            << s.triangulation_angle_deg[k] << " deg, epi " << std::setprecision(0)
            << std::fmod(std::round(s.epipolar_direction_deg[k]), 180.0) << ")";
        out.unsetf(std::ios::fixed);
        out << std::setprecision(6);
      }
    }
    out << (s.gantry_t_group ? " [T group]" : "") << "\n      why: " << s.reason << "\n";
  }
  out << "workspace_info took " << std::fixed << std::setprecision(3) << seconds << " s\n";
  return out.str();
}

}  // namespace hairmvs
