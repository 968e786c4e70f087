#include "src/synthetic/sparse_points.h"

#include <algorithm>
#include <cmath>

#include "src/core/depth_geometry.h"
#include "src/core/logging.h"
#include "src/synthetic/hair_model.h"

namespace hairmvs {

Reconstruction MakeSparseModel(const std::vector<SyntheticView>& views,
                               const std::vector<RenderedView>& renders, int samples_per_view,
                               uint64_t seed) {
  CHECK_EQ(views.size(), renders.size());
  CHECK(!views.empty());
  Reconstruction model;
  Camera camera;
  camera.camera_id = 1;
  camera.model_id = 1;  // PINHOLE
  camera.width = views[0].width;
  camera.height = views[0].height;
  camera.params = {views[0].K(0, 0), views[0].K(1, 1), views[0].K(0, 2), views[0].K(1, 2)};
  model.cameras[1] = camera;
  for (size_t v = 0; v < views.size(); ++v) {
    Image image;
    image.image_id = static_cast<uint32_t>(v + 1);
    image.camera_id = 1;
    image.name = views[v].name;
    image.cam_from_world_rotation = Eigen::Quaterniond(views[v].R).normalized();
    image.cam_from_world_translation = views[v].t;
    model.images[image.image_id] = image;
  }
  model.SortImageOrder();

  uint64_t next_id = 1;
  for (size_t i = 0; i < views.size(); ++i) {
    const SyntheticView& vi = views[i];
    const RenderedView& ri = renders[i];
    const int W = vi.width, H = vi.height;
    std::vector<int64_t> foreground;
    for (int64_t p = 0; p < static_cast<int64_t>(W) * H; ++p) {
      if (ri.label[p] != 0) foreground.push_back(p);
    }
    if (foreground.empty()) continue;
    // A fixed random subset of the foreground pixels (partial Fisher-Yates), in pixel order.
    SplitMix64 rng(DeriveSeed(seed, 3, i));
    const size_t k = std::min<size_t>(samples_per_view, foreground.size());
    for (size_t a = 0; a < k; ++a) {
      const size_t b = a + static_cast<size_t>(rng.Uniform() * (foreground.size() - a));
      std::swap(foreground[a], foreground[std::min(b, foreground.size() - 1)]);
    }
    std::vector<int64_t> chosen(foreground.begin(), foreground.begin() + k);
    std::sort(chosen.begin(), chosen.end());

    for (int64_t p : chosen) {
      const int row = static_cast<int>(p / W), col = static_cast<int>(p % W);
      const double depth = ri.depth.At(row, col);
      const Eigen::Vector3d x_world = BackProjectPixelToWorld(vi.K, vi.R, vi.t, col, row, depth);
      struct Obs {
        size_t view;
        Eigen::Vector2d xy;
      };
      std::vector<Obs> observations = {{i, Eigen::Vector2d(col + 0.5, row + 0.5)}};
      for (size_t j = 0; j < views.size(); ++j) {
        if (j == i) continue;
        const Eigen::Vector3d xc = views[j].ToCamera(x_world);
        if (xc.z() <= 0.0) continue;
        const Eigen::Vector2d xy = views[j].Project(xc);
        if (!(xy.x() >= 0 && xy.x() < W && xy.y() >= 0 && xy.y() < H)) continue;
        const float dj = renders[j].depth.At(static_cast<int>(xy.y()), static_cast<int>(xy.x()));
        const double tolerance_m = 2.0 * xc.z() / views[j].K(0, 0);
        if (dj > 0.0f && std::abs(dj - xc.z()) <= tolerance_m) observations.push_back({j, xy});
      }
      if (observations.size() < 2) continue;
      Point3D point;
      point.point3D_id = next_id++;
      point.xyz = x_world;
      for (int c = 0; c < 3; ++c) point.rgb[c] = ri.rgb[3 * p + c];
      point.error = 0.0;  // the observations are exact projections
      for (const Obs& o : observations) {
        Image& image = model.images.at(static_cast<uint32_t>(o.view + 1));
        Point2D p2d;
        p2d.xy = o.xy;
        p2d.point3D_id = point.point3D_id;
        point.track.push_back({image.image_id, static_cast<uint32_t>(image.points2D.size())});
        image.points2D.push_back(p2d);
      }
      model.points3D[point.point3D_id] = point;
    }
  }
  return model;
}

}  // namespace hairmvs
