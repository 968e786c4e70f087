#pragma once
// COLMAP's geometric pass as a prior on a view's depth: the other views' depth maps. A depth D
// at pixel p costs weight * cost_scale * mean over the views of min(e, max_error_px) /
// max_error_px, e the forward-backward reprojection error (level-0 pixels) of p's point at D
// through that view's map (ForwardBackwardErrorPx, src/stereo/consistency_filter.h); a view that
// does not see the point or has no depth there counts as max_error_px (COLMAP's
// geom_consistency_max_cost). cost_scale: the median over the pixels of the data term's range
// across the coarse labels, so that weight is relative to the data term whatever its units.
// On the device (kernels/geometric_prior.cl); AddGeometricPriorCpu is the plain reference.

#include <cstdint>
#include <vector>

#include "src/fusion/fusion_view.h"
#include "src/opencl/opencl.h"
#include "src/stereo/stereo_geometry.h"

namespace hairmvs {

class OpenCLContext;

struct GeometricPrior {
  std::vector<const FusionView*> views;
  double weight = 0;
  double max_error_px = 0;
};

// The prior added to a host volume ([label][row][col] on the grid of `grid_camera`, whose pixels
// are `level0_px_per_grid_px` level-0 pixels wide) for labels v = base(p) + k * step (base empty
// = 0), k < num_labels, at the pixels where `active` is non-zero (empty: every pixel). Outside the
// masks the data term is 0 at every label and the depths are not kept: the prior there would
// be most of the work (a gantry view's mask covers a fifth of it) and would only pull the
// masks' borders through the smoothness towards whatever the other views see behind them.
class GeometricPriorCL {
 public:
  // Uploads the views' depth maps (the views need not outlive this object).
  GeometricPriorCL(OpenCLContext* context, const GeometricPrior& prior);
  void Add(const StereoCamera& grid_camera, double level0_px_per_grid_px,
           const DepthLabels& labels, const std::vector<float>& base, float step,
           int num_labels, const std::vector<uint8_t>& active, float cost_scale,
           std::vector<float>* volume);

 private:
  struct ViewCamera {
    Eigen::Matrix3d K, R;
    Eigen::Vector3d t;
  };
  OpenCLContext* context_;
  std::vector<ViewCamera> cameras_;
  int num_views_ = 0;
  double weight_ = 0;
  double max_error_px_ = 0;
  cl::Buffer depth_maps_;
  cl::Buffer view_dims_;
  cl::Kernel kernel_;
};

// The same in plain C++ and double precision (the kernel's test reference).
void AddGeometricPriorCpu(const GeometricPrior& prior, const StereoCamera& grid_camera,
                          double level0_px_per_grid_px, const DepthLabels& labels,
                          const std::vector<float>& base, float step, int num_labels,
                          const std::vector<uint8_t>& active, float cost_scale,
                          std::vector<float>* volume);

}  // namespace hairmvs
