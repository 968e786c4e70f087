#pragma once
// CPU renderer of the synthetic hair: strands as round tubes (capsules around the densified
// Catmull-Rom centrelines) and the head proxy as skin, one directional light, a plain
// background.
//   - Ground truth: per pixel, the exact first hit along the ray through the pixel CENTRE
//     (col + 0.5, row + 0.5): planar depth, label (0 background, 1 skin, 2 hair), strand id.
//   - Colour: strands are sub-pixel wide, so each short piece of tube adds its analytic
//     coverage (projected width x length) to the pixels around it with a bilinear (tent)
//     filter, composited front to back in depth order (over the head / background, which are
//     supersampled). Shading is Kajiya-Kay: diffuse sin(T, L), specular from T . H, where T
//     is the strand tangent; the head shadows the light.
// Rows are rendered in bands in parallel (OpenMP); each band is computed from the same inputs
// in a fixed order, so the output does not depend on the number of threads.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "src/core/float_map.h"
#include "src/synthetic/camera_rig.h"
#include "src/synthetic/hair_model.h"

namespace hairmvs {

struct RenderSettings {
  Eigen::Vector3d light_direction = Eigen::Vector3d(0.25, 0.35, 1.0).normalized();  // to light
  double light_intensity = 2.2;
  double ambient = 0.35;
  double specular = 0.12;
  double specular_exponent = 80.0;
  Eigen::Vector3d skin_albedo = Eigen::Vector3d(0.55, 0.38, 0.30);   // linear RGB
  Eigen::Vector3d background = Eigen::Vector3d(0.216, 0.216, 0.216);  // sRGB 128 grey
  int head_supersampling = 3;  // per axis
  // Fraction of a strand's projected area that is opaque (hair transmits a little light).
  double strand_opacity = 0.9;
};

struct RenderedView {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb;        // H x W x 3, sRGB
  FloatMap depth;                  // planar z-depth (m) of the centre ray's first hit; 0 = none
  std::vector<uint8_t> label;      // H x W: 0 background, 1 skin, 2 hair
  std::vector<int32_t> strand_id;  // H x W: hair strand of the hit, -1 otherwise
  std::vector<float> hair_opacity; // H x W: 1 - transmittance of the hair in front of the head
};

struct RayHit {
  double depth = 0;  // planar z in the camera frame, 0 = no hit
  int label = 0;
  int strand = -1;
};

class HairScene {
 public:
  HairScene(HeadModel head, DenseStrands strands, std::vector<Eigen::Vector3f> strand_albedo,
            std::vector<float> strand_layer, RenderSettings settings);

  RenderedView Render(const SyntheticView& view) const;

  // The exact first hit along the ray through image point (x, y) (SfM convention), by brute
  // force over the tube pieces of every block whose bounding sphere the ray meets: slow, a
  // reference for tests.
  RayHit CastRay(const SyntheticView& view, double x, double y) const;

  const DenseStrands& Strands() const { return strands_; }
  const HeadModel& Head() const { return head_; }

 private:
  HeadModel head_;
  DenseStrands strands_;
  std::vector<Eigen::Vector3f> albedo_;
  std::vector<float> layer_;
  RenderSettings settings_;
  // Blocks of up to 16 consecutive tube pieces of a strand with a bounding sphere (centre,
  // radius including the tube), for CastRay.
  struct Block {
    Eigen::Vector3d centre;
    double radius;
    int64_t first, last;  // pieces [first, last): piece i joins points i and i + 1
  };
  std::vector<Block> blocks_;
};

// The first hit t > 0 (along the unit direction `dir` from `origin`) of the capsule of radius r
// around segment [a, b], or -1. Exact (cylinder body and both spherical caps).
double IntersectCapsule(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                        const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r);

// Linear [0, 1] to 8-bit sRGB.
uint8_t LinearToSrgb8(double v);

}  // namespace hairmvs
