#pragma once
// Two-view geometry of orientation stereo: the per-view projection of a reference pixel at a
// given depth (as a matrix and a vector, so a kernel needs no per-slice homography), the
// epipole roll correction of paper Eq. 5 and the plane-homography transfer of orientations
// that replaces it by default, and the depth labels.
// Pixel convention: SfM (pixel (col, row) is centred at image point (col + 0.5, row + 0.5)).

#include <Eigen/Core>
#include <array>

#include "hairmvs/orientation_stereo.h"
#include "src/core/depth_geometry.h"  // StereoCamera
#include "src/core/float_map.h"

namespace hairmvs {

// u = D * H * (x, y, 1) + b maps the reference image point (x, y) at z-depth D to homogeneous
// image coordinates of the source (both on the grids their cameras are for).
struct ViewProjection {
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  // psi = 2 (phi_ref - phi_src): multiply O_ref* O_src by exp(i psi) (paper Eq. 5).
  double psi_rad = 0;
  // Map each reference orientation through the plane homography instead (psi unused).
  bool plane_homography = false;
  // The 16 floats the cost kernels read: H row-major, b, cos psi, sin psi, plane_homography
  // (0 or 1), and `weight`, the view's factor in the orientation cost's sum over the views
  // (CostViewInput::weight; the photometric kernel does not read it).
  std::array<float, 16> Packed(float weight) const;
};

// ref, src: the cameras of the grids the map goes between (a pyramid level's:
// StereoCamera::PyramidLevel).
ViewProjection ComputeViewProjection(const StereoCamera& ref, const StereoCamera& src,
                                     OrientationTransfer transfer);

// Pixels of pyramid level `level` per pixel of level `grid_level`: 2^(grid_level - level)
// (the levels halve exactly and share the image origin).
double LevelPixelsPerPixel(int level, int grid_level);

// The level-0 pixel (column or row) nearest the centre of pixel `index` of pyramid level
// `level`, for a level-0 size of size0 pixels.
int NearestLevel0Pixel(int index, int level, int size0);

// The direction, in the source image, of a strand that passes through the reference image
// point (x, y) at depth D with direction t = (dx, dy) and lies in a plane: the Jacobian at
// (x, y) of the map through that plane into the source, applied to t. The plane is given by the
// gradient g of its log depth at (x, y) (pixel units; zero: fronto-parallel): its points near
// (x, y) lie at 1 / z(x + d) = (1 - g . d) / D, so the strand's 3D direction is
// D K^-1 ((t, 0) + (g . t) (x, y, 1)) and the source sees H times that. Scaled by an
// unspecified positive factor.
Eigen::Vector2d TransferDirection(const ViewProjection& projection, double depth, double x,
                                  double y, const Eigen::Vector2d& direction,
                                  const Eigen::Vector2d& log_depth_gradient =
                                      Eigen::Vector2d::Zero());

// The tilt of a surface as TransferDirection takes it: the gradient of log depth at the pixels
// of pyramid level `level` (width x height; 2 channels, x and y, in that level's pixel units)
// of a depth map on the level-0 grid (metres, 0 = none), by central differences over
// +-max(2, 2^level) level-0 pixels around the level pixel's NearestLevel0Pixel;
// 0 where one of the four has no depth. Clamped where the plane they make, on the optical axis,
// would be seen at more than max_tilt_deg from the image plane: where the gradient times the
// focal lengths (level 0's, in x and in y: the gradient per unit of normalised image
// coordinates) is longer than tan(max_tilt_deg); its direction there kept.
FloatMap LogDepthGradient(const FloatMap& depth0, int level, int width, int height,
                          double focal_x_px, double focal_y_px, double max_tilt_deg);

// The epipole of the camera centred at `other_center` in `camera`'s image, homogeneous
// (K (R c + t)): z = 0 where it lies at infinity, z < 0 where `other_center` is behind.
Eigen::Vector3d Epipole(const StereoCamera& camera, const Eigen::Vector3d& other_center);

// Whether that epipole lies within `camera`'s image (x in [0, width], y in [0, height], image
// coordinates): the other camera is ahead of or behind this one rather than beside it.
bool EpipoleInImage(const StereoCamera& camera, const Eigen::Vector3d& other_center);

// Angle (radians, modulo pi is what matters) between the image +x axis and the vector from the
// principal point of `camera` to the epipole of the camera centred at `other_center`.
double EpipoleAngle(const StereoCamera& camera, const Eigen::Vector3d& other_center);

// The angle in degrees between two cameras' optical axes.
double ViewingAngleDeg(const StereoCamera& a, const StereoCamera& b);

// How much larger `src` images the point of the reference's optical axis at z-depth `depth`
// than the reference does: (f_src / z_src) / (f_ref / depth), the focal lengths (MeanFocalPx)
// over each camera's z-depth of the point; 0 when the point lies behind `src`. The orientation
// fields' filters are in pixels: across a ratio far from 1 they see the strands at other
// scales.
double ImageScaleRatio(const StereoCamera& ref, const StereoCamera& src, double depth);

// Depth labels: label value v in [0, num_labels - 1] (fractional values allowed) maps to
// t = a + b v, depth = t (uniform in depth) or 1 / t (uniform in inverse depth).
struct DepthLabels {
  double depth_min = 0;
  double depth_max = 0;
  int num_labels = 0;
  bool inverse = true;
  double a = 0;
  double b = 0;

  DepthLabels() = default;
  DepthLabels(double depth_min, double depth_max, int num_labels, bool inverse);
  double Depth(double v) const {
    const double t = a + b * v;
    return inverse ? 1.0 / t : t;
  }
  // Inverse of Depth().
  double Label(double depth) const { return ((inverse ? 1.0 / depth : depth) - a) / b; }
  // The label in the middle of the range, (num_labels - 1) / 2.
  double MiddleLabel() const { return 0.5 * (num_labels - 1); }
};

// The disparity step of one label in the middle of the range, v = (num_labels - 1) / 2, for
// a source one radian of view angle away: the reference's focal length (MeanFocalPx) times the
// labels' relative depth step there, |1 / Depth(v) - 1 / Depth(v + 1)| * (Depth(v) +
// Depth(v + 1)) / 2. Grows with the image size and the labels' spacing (num_depths, the
// range); a real source's step is this times its angle, about.
double LabelStepPxPerRadian(const StereoCamera& ref, const DepthLabels& labels);

}  // namespace hairmvs
