#pragma once
// Procedural hair on an ellipsoidal head proxy: the geometry the synthetic renderer draws and
// the ground truth it writes. World: metres, +Z up, the face towards -Y (shared data README).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "hairmvs/synthesize.h"

namespace hairmvs {

// A deterministic random stream (SplitMix64): the same seed gives the same numbers on every
// platform and standard library, unlike std::uniform_real_distribution.
class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}
  uint64_t Next();
  double Uniform();                       // [0, 1)
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  double Normal();                        // standard normal (Box-Muller, no caching)
 private:
  uint64_t state_;
};
// A seed for item `index` of stream `stream` derived from the user's seed.
uint64_t DeriveSeed(uint64_t seed, uint64_t stream, uint64_t index);

struct HeadModel {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d semi_axes = Eigen::Vector3d(0.08, 0.10, 0.11);  // as the shared sets

  // The first hit t > 0 of origin + t * direction, or -1 if none.
  double Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;
  // Outward unit normal at a point on (or near) the surface.
  Eigen::Vector3d Normal(const Eigen::Vector3d& point) const;
  // (x/a)^2 + (y/b)^2 + (z/c)^2 of the point relative to the centre, with the axes grown by
  // `offset_m`: < 1 inside that shell.
  double ShellValue(const Eigen::Vector3d& point, double offset_m) const;
};

struct HairStrands {
  std::vector<Eigen::Vector3f> points;  // all strands, root first
  std::vector<int64_t> offsets;         // strand i is points[offsets[i], offsets[i+1])
  std::vector<float> layer;             // per strand: 0 = next to the scalp, 1 = outermost
  std::vector<Eigen::Vector3f> albedo;  // per strand, linear RGB

  int NumStrands() const { return static_cast<int>(offsets.size()) - 1; }
  Eigen::Vector3d BoundingBoxCentre() const;
};

struct HairGenerationOptions {
  HairStyle style = HairStyle::kStraight;
  int num_strands = 12000;
  uint64_t seed = 1;
};

// Roots on the upper part of the head (a hairline rising towards the face), growing outward,
// combed back and falling under gravity around the head; each strand settles in its own layer
// above the scalp so the hair is a volume. `curly` adds helical curls around that path.
HairStrands GenerateHair(const HeadModel& head, const HairGenerationOptions& options);

// Strands given from outside (a data set's gt/strands_*.npy, root first) made renderable: each
// strand's layer from the median height of its points above the head's surface, on
// GenerateHair's scale (a layer settles 1 + 14 * layer mm above the scalp; clamped to [0, 1]),
// and a dark-brown albedo drawn as GenerateHair draws it, from its own stream of `seed`.
HairStrands HairFromStrands(const HeadModel& head, std::vector<Eigen::Vector3f> points,
                            std::vector<int64_t> offsets, uint64_t seed);

// Strands resampled along their uniform Catmull-Rom splines (end points repeated, as the
// evaluation's StrandDistance and Blender do: p_{-1} = p_0), every stored point kept, at most
// `max_spacing_m` apart; with the tube radius of each point (linear in the stored index from root
// to tip).
struct DenseStrands {
  std::vector<Eigen::Vector3f> points;
  std::vector<float> radius_m;
  std::vector<int32_t> strand;   // strand index of each point
  std::vector<int64_t> offsets;  // per strand, as HairStrands
};
DenseStrands DensifyStrands(const HairStrands& hair, double max_spacing_m, double root_diameter_m,
                            double tip_diameter_m);

// Distance from x to the polyline points[begin, end).
double DistanceToPolyline(const std::vector<Eigen::Vector3f>& points, int64_t begin, int64_t end,
                          const Eigen::Vector3d& x);

}  // namespace hairmvs
