#include "src/stereo/geometric_prior.h"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <string>

#include "src/core/logging.h"
#include "src/opencl/opencl_context.h"
#include "src/stereo/consistency_filter.h"

namespace hairmvs {

namespace {
// Labels per work-item (LABEL_CHUNK in kernels/geometric_prior.cl).
constexpr int kLabelChunk = 16;
}  // namespace

GeometricPriorCL::GeometricPriorCL(OpenCLContext* context, const GeometricPrior& prior)
    : context_(context),
      num_views_(static_cast<int>(prior.views.size())),
      weight_(prior.weight),
      max_error_px_(prior.max_error_px),
      kernel_(context->Program({"geometric_prior.cl"},
                               "-D LABEL_CHUNK=" + std::to_string(kLabelChunk)),
              "geometric_prior") {
  std::vector<float> maps;
  std::vector<int> dims;
  for (const FusionView* view : prior.views) {
    cameras_.push_back({view->K, view->R, view->t});
    const std::array<int, 4> plane =
        ConcatenatedPlaneDims(view->depth.Width(), view->depth.Height(), maps.size());
    dims.insert(dims.end(), plane.begin(), plane.end());
    dims.push_back(view->col0);
    dims.push_back(view->row0);
    maps.insert(maps.end(), view->depth.Data().begin(), view->depth.Data().end());
  }
  depth_maps_ = ReadOnlyBuffer(context, maps);
  view_dims_ = ReadOnlyBuffer(context, dims);
}

void GeometricPriorCL::Add(const StereoCamera& grid_camera, double level0_px_per_grid_px,
                           const DepthLabels& labels, const std::vector<float>& base,
                           float step, int num_labels, const std::vector<uint8_t>& active,
                           float cost_scale, std::vector<float>* volume) {
  if (num_views_ == 0 || !(weight_ > 0) || num_labels < 1) return;
  const int width = grid_camera.width, height = grid_camera.height;
  const size_t n = static_cast<size_t>(width) * height;
  CHECK_EQ(volume->size(), n * num_labels);
  CHECK(base.empty() || base.size() == n);
  CHECK(active.empty() || active.size() == n);
  // Everything in the reference camera's frame (kernels/geometric_prior.cl), so that single
  // precision keeps the errors to about 1e-4 px; what depends on a view only is computed here.
  const Eigen::Matrix3d R_t = grid_camera.R.transpose();
  std::array<float, 9> ref_params;
  const Eigen::Matrix3d K_inv = grid_camera.K.inverse();
  for (int i = 0; i < 9; ++i) ref_params[i] = static_cast<float>(K_inv(i / 3, i % 3));
  std::vector<float> view_params;
  for (const ViewCamera& view : cameras_) {
    const Eigen::Matrix3d A = view.R * R_t;
    const Eigen::Vector3d a = view.t - A * grid_camera.t;
    const Eigen::Vector3d centre = grid_camera.R * (-view.R.transpose() * view.t) + grid_camera.t;
    const Eigen::Matrix3d KA = view.K * A;
    const Eigen::Vector3d Ka = view.K * a;
    const Eigen::Vector3d K_ref_centre = grid_camera.K * centre;
    for (int i = 0; i < 9; ++i) view_params.push_back(static_cast<float>(KA(i / 3, i % 3)));
    for (int i = 0; i < 3; ++i) view_params.push_back(static_cast<float>(A(2, i)));
    for (int i = 0; i < 3; ++i) view_params.push_back(static_cast<float>(Ka(i)));
    view_params.push_back(static_cast<float>(a(2)));
    for (int i = 0; i < 3; ++i) view_params.push_back(static_cast<float>(K_ref_centre(i)));
    view_params.push_back(0.0f);
  }
  const float no_base = 0.0f;
  const uint8_t all_active = 1;
  cl::Buffer ref_buffer = ReadOnlyBuffer(context_, ref_params);
  cl::Buffer params_buffer = ReadOnlyBuffer(context_, view_params);
  cl::Buffer base_buffer = base.empty() ? ReadOnlyBuffer(context_, &no_base, sizeof(float))
                                        : ReadOnlyBuffer(context_, base);
  cl::Buffer active_buffer = active.empty() ? ReadOnlyBuffer(context_, &all_active, 1)
                                            : ReadOnlyBuffer(context_, active);
  // The host volume itself (a CPU device adds in place; another copies it there and back).
  cl::Buffer volume_buffer = context_->Buffer(CL_MEM_READ_WRITE | CL_MEM_USE_HOST_PTR,
                           sizeof(float) * volume->size(), volume->data());
  const float per_view =
      static_cast<float>(weight_ * cost_scale / num_views_);
  cl::Kernel& k = kernel_;
  int arg = 0;
  k.setArg(arg++, width);
  k.setArg(arg++, height);
  k.setArg(arg++, ref_buffer);
  k.setArg(arg++, depth_maps_);
  k.setArg(arg++, params_buffer);
  k.setArg(arg++, view_dims_);
  k.setArg(arg++, num_views_);
  k.setArg(arg++, num_labels);
  k.setArg(arg++, base_buffer);
  k.setArg(arg++, base.empty() ? 0 : 1);
  k.setArg(arg++, active_buffer);
  k.setArg(arg++, active.empty() ? 0 : 1);
  k.setArg(arg++, step);
  k.setArg(arg++, static_cast<float>(labels.a));
  k.setArg(arg++, static_cast<float>(labels.b));
  k.setArg(arg++, static_cast<int>(labels.inverse));
  k.setArg(arg++, static_cast<float>(max_error_px_));
  k.setArg(arg++, static_cast<float>(level0_px_per_grid_px));
  k.setArg(arg++, per_view);
  k.setArg(arg++, volume_buffer);
  cl::CommandQueue& queue = context_->Queue();
  queue.enqueueNDRangeKernel(k, cl::NullRange,
                             cl::NDRange(width, height, DivideRoundingUp(num_labels, kLabelChunk)));
  void* mapped = queue.enqueueMapBuffer(volume_buffer, CL_TRUE, CL_MAP_READ, 0,
                                        sizeof(float) * volume->size());
  CHECK(mapped == volume->data());  // USE_HOST_PTR: the map is the host memory, up to date
  queue.enqueueUnmapMemObject(volume_buffer, mapped);
  queue.finish();
}

void AddGeometricPriorCpu(const GeometricPrior& prior, const StereoCamera& grid_camera,
                          double level0_px_per_grid_px, const DepthLabels& labels,
                          const std::vector<float>& base, float step, int num_labels,
                          const std::vector<uint8_t>& active, float cost_scale,
                          std::vector<float>* volume) {
  if (prior.views.empty() || !(prior.weight > 0)) return;
  const int width = grid_camera.width, height = grid_camera.height;
  const size_t n = static_cast<size_t>(width) * height;
  CHECK_EQ(volume->size(), n * num_labels);
  const Eigen::Matrix3d K_inv = grid_camera.K.inverse();
  const Eigen::Matrix3d R_t = grid_camera.R.transpose();
  const double max_error = prior.max_error_px;
  const float per_view =
      static_cast<float>(prior.weight * cost_scale / prior.views.size());
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const size_t p = static_cast<size_t>(row) * width + col;
      if (!active.empty() && active[p] == 0) continue;
      const Eigen::Vector3d ray = K_inv * Eigen::Vector3d(col + 0.5, row + 0.5, 1.0);
      const Eigen::Vector2d centre(col + 0.5, row + 0.5);
      for (int k = 0; k < num_labels; ++k) {
        const double depth = labels.Depth((base.empty() ? 0.0f : base[p]) + k * step);
        const Eigen::Vector3d world = R_t * (ray * depth - grid_camera.t);
        double total = 0;
        for (const FusionView* view : prior.views) {
          double error_px;
          const bool seen = ForwardBackwardErrorPx(*view, world, grid_camera.K, grid_camera.R,
                                                   grid_camera.t, centre, &error_px);
          total += seen ? std::min(max_error, error_px * level0_px_per_grid_px) / max_error
                        : 1.0;
        }
        (*volume)[static_cast<size_t>(k) * n + p] += per_view * static_cast<float>(total);
      }
    }
  }
}

}  // namespace hairmvs
