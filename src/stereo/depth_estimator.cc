#include "src/stereo/depth_estimator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "src/core/logging.h"
#include "src/core/progress.h"
#include "src/mrf/mrf.h"
#include "src/opencl/opencl_context.h"
#include "src/stereo/cost_volume.h"
#include "src/stereo/guided_filter.h"

namespace hairmvs {

std::vector<float> SubpixelOffsets(const std::vector<float>& volume, int num_pixels,
                                   int num_labels, const std::vector<int>& labels) {
  std::vector<float> offsets(num_pixels, 0.0f);
  for (int p = 0; p < num_pixels; ++p) {
    const int l = labels[p];
    if (l <= 0 || l >= num_labels - 1) continue;
    const double em = volume[static_cast<size_t>(l - 1) * num_pixels + p];
    const double e0 = volume[static_cast<size_t>(l) * num_pixels + p];
    const double ep = volume[static_cast<size_t>(l + 1) * num_pixels + p];
    if (em < e0 && em <= ep) {
      offsets[p] = -0.5f;
    } else if (ep < e0 && ep < em) {
      offsets[p] = 0.5f;
    } else {
      const double denom = em - 2 * e0 + ep;
      if (denom > 0) {
        offsets[p] = static_cast<float>(std::clamp(0.5 * (em - ep) / denom, -0.5, 0.5));
      }
    }
  }
  return offsets;
}

void SmoothnessWeights(const FloatMap& orientation, double lambda, double sigma_o,
                       std::vector<float>* weight_right, std::vector<float>* weight_down) {
  const int w = orientation.Width(), h = orientation.Height();
  weight_right->assign(static_cast<size_t>(w) * h, 0.0f);
  weight_down->assign(static_cast<size_t>(w) * h, 0.0f);
  const double scale = 1.0 / (2.0 * sigma_o * sigma_o);
  auto weight = [&](int r0, int c0, int r1, int c1) {
    const double d0 = orientation.At(r0, c0, 0) - orientation.At(r1, c1, 0);
    const double d1 = orientation.At(r0, c0, 1) - orientation.At(r1, c1, 1);
    return static_cast<float>(lambda * std::exp(-(d0 * d0 + d1 * d1) * scale));
  };
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      if (col + 1 < w) (*weight_right)[row * w + col] = weight(row, col, row, col + 1);
      if (row + 1 < h) (*weight_down)[row * w + col] = weight(row, col, row + 1, col);
    }
  }
}

double MeanSquareOfNonZero(const FloatMap& field) {
  double sum_sq = 0;
  long count = 0;
  for (size_t i = 0; i < field.NumPixels(); ++i) {
    double sq = 0;
    for (int c = 0; c < field.Channels(); ++c) sq += field.Channel(c)[i] * field.Channel(c)[i];
    sum_sq += sq;
    count += sq > 0;
  }
  return count == 0 ? 0.0 : sum_sq / count;
}

FloatMap ScaleToRms(const FloatMap& field, double rms) {
  const double mean_sq = MeanSquareOfNonZero(field);
  FloatMap scaled = field;
  if (mean_sq == 0) return scaled;
  const float factor = static_cast<float>(rms / std::sqrt(mean_sq));
  for (float& v : scaled.Data()) v *= factor;
  return scaled;
}

namespace {

// The data term is scaled as the sum of this many levels (the paper's, num_levels' default),
// whatever the levels used, so that lambda means the same with any num_levels.
constexpr int kDataTermLevelsScale = 3;

// Per-level machinery of one reference view.
struct LevelPipeline {
  // The data term's costs (one, or orientation then colour when combined), each with its
  // weight and its index in DataTerms(); with best_source_fraction < 1, one per term and
  // source, each term's sources in the same order at every level.
  struct Cost {
    std::unique_ptr<CostVolumeCL> volume;
    float weight;
    int term;
  };
  std::vector<Cost> costs;
  std::unique_ptr<GuidedFilterCL> filter;
  int width = 0;
  int height = 0;
};

MrfSolverOptions MakeMrfOptions(const OrientationStereoOptions& options) {
  MrfSolverOptions mrf;
  THROW_IF(!FromString(options.mrf_solver, &mrf.solver),
           "--OrientationStereo.mrf_solver: unknown solver '" << options.mrf_solver << "'");
  mrf.max_cycles = options.mrf_max_cycles;
  mrf.icm_polish_iterations = options.mrf_icm_polish_iterations;
  return mrf;
}

// Sums over the (2 radius + 1)^2 window of each pixel, clipped at the image's edges, in double
// so that the means taken from them keep a float field's precision.
cv::Mat WindowSums(const float* in, int width, int height, int radius) {
  cv::Mat sums;
  cv::Mat(height, width, CV_32FC1, const_cast<float*>(in)).convertTo(sums, CV_64FC1);
  const int size = 2 * radius + 1;
  cv::boxFilter(sums, sums, -1, cv::Size(size, size), cv::Point(-1, -1), /*normalize=*/false,
                cv::BORDER_CONSTANT);
  return sums;
}

// Labels v = base(p) + k * step in front of the pixel's bound label get the pixel's worst cost
// plus its cost range per label of excess, so that the MRF is pulled back behind the bound even
// where a whole band lies in front of it. bound_label: per pixel, -inf = none.
void PenalizeInFrontOfBound(const std::vector<float>& bound_label,
                            const std::vector<float>& base, float step, int num_labels,
                            std::vector<float>* volume) {
  const size_t n = bound_label.size();
  for (size_t p = 0; p < n; ++p) {
    const float bound = bound_label[p];
    if (!std::isfinite(bound)) continue;
    const float base_p = base.empty() ? 0.0f : base[p];
    if (base_p >= bound) continue;
    float best = std::numeric_limits<float>::infinity(), worst = -best;
    for (int k = 0; k < num_labels; ++k) {
      const float c = (*volume)[k * n + p];
      best = std::min(best, c);
      worst = std::max(worst, c);
    }
    const float range = std::max(worst - best, 1e-6f);
    for (int k = 0; k < num_labels; ++k) {
      const float v = base_p + k * step;
      if (v < bound) (*volume)[k * n + p] = worst + range * (bound - v);
    }
  }
}

// The coarse stage's first label at the pixels of pyramid level `level` (width x height) when
// its labels start at the visual hull: the depth bound's label (`bound_labels0`, level-0 grid
// width0 x height0, -inf = none) at the level pixel's NearestLevel0Pixel; 0 where there is
// none. At most the label from which num_labels labels end at 10 x depth_max, only so that the
// band's depths stay finite in inverse depth (labels past the range's far end cost time, not
// accuracy: an estimate there is filtered as outside the range).
std::vector<float> VisualHullLabelBase(const std::vector<float>& bound_labels0, int width0,
                                       int height0, const DepthLabels& labels, int level,
                                       int width, int height) {
  const float top = static_cast<float>(
      std::max(0.0, labels.Label(10 * labels.depth_max) - (labels.num_labels - 1)));
  std::vector<float> base(static_cast<size_t>(width) * height, 0.0f);
  for (int r = 0; r < height; ++r) {
    const int r0 = NearestLevel0Pixel(r, level, height0);
    for (int c = 0; c < width; ++c) {
      const float bound = bound_labels0[static_cast<size_t>(r0) * width0 +
                                        NearestLevel0Pixel(c, level, width0)];
      if (std::isfinite(bound)) {
        base[static_cast<size_t>(r) * width + c] = std::clamp(bound, 0.0f, top);
      }
    }
  }
  return base;
}

// The coarse volume ([k][pixel], label base[p] + k) on the range's labels 0 .. num_labels - 1,
// linearly interpolated between the two nearest k; labels in front of base[p] get the pixel's
// largest cost.
FloatMap CostOnRangeLabels(const std::vector<float>& volume, const std::vector<float>& base,
                           int width, int height, int num_labels) {
  const size_t n = static_cast<size_t>(width) * height;
  FloatMap out(width, height, num_labels);
  for (size_t p = 0; p < n; ++p) {
    float worst = -std::numeric_limits<float>::infinity();
    for (int k = 0; k < num_labels; ++k) worst = std::max(worst, volume[k * n + p]);
    for (int j = 0; j < num_labels; ++j) {
      const float x = j - base[p];
      float cost = worst;
      if (x >= 0) {
        const int k0 = std::min(static_cast<int>(x), num_labels - 1);
        const int k1 = std::min(k0 + 1, num_labels - 1);
        const float f = x - k0;
        cost = f > 0 ? (1 - f) * volume[k0 * n + p] + f * volume[k1 * n + p]
                     : volume[k0 * n + p];
      }
      out.Channel(j)[p] = cost;
    }
  }
  return out;
}

}  // namespace

namespace {

// The median of the cost's range across labels over the pixels with contrast (above 1e-3 of the
// largest range: masked pixels cost 0 at every label, up to rounding).
float MedianCostRange(const std::vector<float>& volume, size_t num_pixels, int num_labels) {
  std::vector<float> ranges;
  ranges.reserve(num_pixels);
  for (size_t p = 0; p < num_pixels; ++p) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (int k = 0; k < num_labels; ++k) {
      const float c = volume[k * num_pixels + p];
      lo = std::min(lo, c);
      hi = std::max(hi, c);
    }
    if (hi > lo) ranges.push_back(hi - lo);
  }
  if (ranges.empty()) return 0.0f;
  const float largest = *std::max_element(ranges.begin(), ranges.end());
  ranges.erase(std::remove_if(ranges.begin(), ranges.end(),
                              [largest](float r) { return r <= 1e-3f * largest; }),
               ranges.end());
  std::nth_element(ranges.begin(), ranges.begin() + ranges.size() / 2, ranges.end());
  return ranges[ranges.size() / 2];
}

}  // namespace

FloatMap NormalizeOrientationField(const FloatMap& orientation, int radius, float relative_eps) {
  CHECK_EQ(orientation.Channels(), 2);
  const int width = orientation.Width(), height = orientation.Height();
  const size_t n = orientation.NumPixels();
  // Means over the valid (non-zero) pixels of each window, so that mask borders do not bias.
  std::vector<float> valid(n), sq(n);
  for (size_t i = 0; i < n; ++i) {
    const float re = orientation.Channel(0)[i], im = orientation.Channel(1)[i];
    valid[i] = (re != 0.0f || im != 0.0f) ? 1.0f : 0.0f;
    sq[i] = re * re + im * im;
  }
  // eps in units of the field's own mean |O|^2, so that the confidence's exponent and the
  // images' contrast do not change what it damps.
  const double eps = relative_eps * MeanSquareOfNonZero(orientation);
  const cv::Mat counts = WindowSums(valid.data(), width, height, radius);
  const cv::Mat sums_re = WindowSums(orientation.Channel(0), width, height, radius);
  const cv::Mat sums_im = WindowSums(orientation.Channel(1), width, height, radius);
  const cv::Mat sums_sq = WindowSums(sq.data(), width, height, radius);
  const auto* count = counts.ptr<double>();
  const auto* sum_re = sums_re.ptr<double>();
  const auto* sum_im = sums_im.ptr<double>();
  const auto* sum_sq = sums_sq.ptr<double>();
  FloatMap out(width, height, 2, 0.0f);
  for (size_t i = 0; i < n; ++i) {
    if (valid[i] == 0.0f || count[i] < 1) continue;
    const double mean_re = sum_re[i] / count[i], mean_im = sum_im[i] / count[i];
    const double variance =
        std::max(0.0, sum_sq[i] / count[i] - mean_re * mean_re - mean_im * mean_im);
    const double scale = 1.0 / std::sqrt(variance + eps);
    out.Channel(0)[i] = static_cast<float>((orientation.Channel(0)[i] - mean_re) * scale);
    out.Channel(1)[i] = static_cast<float>((orientation.Channel(1)[i] - mean_im) * scale);
  }
  return out;
}

int SliceBlockThatFits(int slice_block, int num_labels, size_t bytes_per_slice,
                       size_t max_alloc_bytes) {
  int block = std::max(1, std::min(slice_block, num_labels));
  if (bytes_per_slice > 0) {
    const size_t fits = max_alloc_bytes / bytes_per_slice;
    block = static_cast<int>(std::max<size_t>(1, std::min<size_t>(block, fits)));
  }
  return block;
}

int CommonPyramidLevels(const StereoViewData& ref,
                        const std::vector<const StereoViewData*>& sources, bool colour) {
  int num_levels = static_cast<int>(ref.orientation.size());
  if (colour) num_levels = std::min<int>(num_levels, static_cast<int>(ref.rgb.size()));
  for (const StereoViewData* src : sources) {
    num_levels = std::min<int>(num_levels, static_cast<int>(src->orientation.size()));
    if (colour) num_levels = std::min<int>(num_levels, static_cast<int>(src->rgb.size()));
  }
  return num_levels;
}

double SourceScaleRatio(const StereoViewData& ref, const StereoViewData& source,
                        const DepthLabels& labels) {
  return ImageScaleRatio(ref.camera, source.camera, labels.Depth(labels.MiddleLabel()));
}

int SourceLevelOffset(double ratio, bool match_scale) {
  return match_scale && ratio > 0 ? static_cast<int>(std::lround(std::log2(ratio))) : 0;
}

int SourceLevel(const StereoViewData& source, int level, int offset, bool colour) {
  int num_levels = static_cast<int>(source.orientation.size());
  if (colour) num_levels = std::min<int>(num_levels, static_cast<int>(source.rgb.size()));
  return std::clamp(level + offset, 0, num_levels - 1);
}

double BestLevelScaleMismatch(const StereoViewData& source, double ratio, int offset,
                              bool colour, int num_levels) {
  if (!(ratio > 0)) return 0;
  double best = std::numeric_limits<double>::infinity();
  for (int l = 0; l < num_levels; ++l) {
    const double r = ratio / std::ldexp(1.0, SourceLevel(source, l, offset, colour) - l);
    best = std::min(best, std::max(r, 1 / r));
  }
  return best;
}

namespace {

// EstimateDepthMap on the reference's whole grid.
DepthEstimate EstimateDepthMapOnGrid(OpenCLContext* context, const StereoViewData& ref,
                                     const std::vector<const StereoViewData*>& sources,
                                     const FloatMap& mask, const FloatMap& visual_hull_entry,
                                     const DepthLabels& labels,
                                     const OrientationStereoOptions& options,
                                     StageTimings* timings, Progress* progress,
                                     const GeometricPrior* prior,
                                     std::vector<float>* coarse_volume_cache) {
  THROW_IF(ref.orientation.empty(), "EstimateDepthMap: the reference has no orientation field");
  THROW_IF(sources.empty(), "EstimateDepthMap: no source views");
  const bool colour = options.MatchesColour();
  // The pyramid levels every view has: the data term's (the first num_levels) and the coarse
  // stage's grid.
  const int num_pyramid_levels = CommonPyramidLevels(ref, sources, colour);
  THROW_IF(num_pyramid_levels < 1, "EstimateDepthMap: no common pyramid level");
  const int num_levels = std::min(options.num_levels, num_pyramid_levels);
  const int width0 = ref.orientation[0].Width();
  const int height0 = ref.orientation[0].Height();
  cl::CommandQueue& queue = context->Queue();
  const MrfSolverOptions mrf_options = MakeMrfOptions(options);

  // The guide of the aggregation and of the smoothness weights (see guide_rms).
  std::vector<FloatMap> scaled_guides;
  for (int l = 0; l < num_pyramid_levels && options.guide_rms > 0; ++l) {
    scaled_guides.push_back(ScaleToRms(ref.orientation[l], options.guide_rms));
  }
  auto guide = [&](int l) -> const FloatMap& {
    return scaled_guides.empty() ? ref.orientation[l] : scaled_guides[l];
  };
  if (!visual_hull_entry.Empty()) {
    CHECK_EQ(visual_hull_entry.Width(), width0);
    CHECK_EQ(visual_hull_entry.Height(), height0);
  }
  const bool strand_plane_from_hull =
      options.StrandPlaneFromVisualHull() && !visual_hull_entry.Empty();
  std::vector<LevelPipeline> levels(num_pyramid_levels);
  for (int l = 0; l < num_pyramid_levels; ++l) {
    levels[l].width = ref.orientation[l].Width();
    levels[l].height = ref.orientation[l].Height();
  }
  const int num_sources = static_cast<int>(sources.size());
  const int num_best_sources = options.NumBestSources(num_sources);
  const bool select_sources = num_best_sources < num_sources;
  std::vector<int> source_level_offsets;
  for (const StereoViewData* src : sources) {
    source_level_offsets.push_back(
        SourceLevelOffset(SourceScaleRatio(ref, *src, labels), options.match_source_scale));
  }
  {
    ScopedStageTimer timer(timings, "cost volume");
    const std::vector<std::pair<StereoCost, float>> terms = options.DataTerms();
    for (int l = 0; l < num_levels; ++l) {
      for (int term = 0; term < static_cast<int>(terms.size()); ++term) {
        const auto& [cost, weight] = terms[term];
        auto matched = [cost = cost](const StereoViewData& view, int level) -> const FloatMap& {
          if (cost == StereoCost::kPhotometric) return view.rgb[level];
          return view.matching.empty() ? view.orientation[level] : view.matching[level];
        };
        // Level cameras as the pyramid makes the levels (CostVolumeCL checks their sizes).
        CostViewInput ref_in{ref.camera.PyramidLevel(l), matched(ref, l)};
        if (strand_plane_from_hull && cost == StereoCost::kOrientation) {
          ref_in.log_depth_gradient = LogDepthGradient(
              visual_hull_entry, l, ref_in.field.Width(), ref_in.field.Height(),
              ref.camera.K(0, 0), ref.camera.K(1, 1), options.max_strand_plane_tilt_deg);
        }
        std::vector<CostViewInput> src_in;
        for (int s = 0; s < num_sources; ++s) {
          const StereoViewData* src = sources[s];
          const int src_level = SourceLevel(*src, l, source_level_offsets[s], colour);
          src_in.push_back({src->camera.PyramidLevel(src_level), matched(*src, src_level)});
          src_in.back().weight = static_cast<float>(options.LevelSourceWeight(
              l, num_levels, ViewingAngleDeg(ref.camera, src->camera)));
        }
        // Selecting sources needs each source's aggregated cost: one volume per source.
        std::vector<std::vector<CostViewInput>> groups;
        if (select_sources) {
          for (const CostViewInput& one : src_in) groups.push_back({one});
        } else {
          groups.push_back(std::move(src_in));
        }
        for (const std::vector<CostViewInput>& group : groups) {
          levels[l].costs.push_back(
              {std::make_unique<CostVolumeCL>(context, cost, ref_in, group,
                                              options.orientation_transfer,
                                              options.ncc_window_px / 2),
               weight, term});
        }
      }
    }
  }
  {
    ScopedStageTimer timer(timings, "aggregation");
    for (int l = 0; l < num_levels; ++l) {
      levels[l].filter = std::make_unique<GuidedFilterCL>(
          context, guide(l), options.WindowPx(l) / 2,
          static_cast<float>(options.guided_filter_eps));
    }
    queue.finish();
  }
  ResampleAccumulateCL resample(context);
  SumBestSourcesCL select(context);  // best_source_fraction < 1

  // The aggregated data term summed over levels on the grid of `grid_level`:
  // [label][row][col] for num_labels labels v = base_l(p) + k * step.
  auto build_volume = [&](int grid_level, int first_level, int num_labels,
                          const std::vector<std::vector<float>>& base, float step) {
    const int gw = levels[grid_level].width, gh = levels[grid_level].height;
    const size_t grid_pixels = static_cast<size_t>(gw) * gh;
    // The device's buffer first: one beyond its largest allocation is refused, naming its size,
    // before the host has filled as much memory.
    cl::Buffer volume =
        context->Buffer(CL_MEM_READ_WRITE, sizeof(float) * grid_pixels * num_labels);
    std::vector<float> host(grid_pixels * num_labels);
    queue.enqueueFillBuffer(volume, 0.0f, 0, sizeof(float) * host.size());
    // The block's largest buffers, per slice at the finest level used: the guided filter's 3
    // planes (GuidedFilterCL), the colour cost's 6 (CostVolumeCL).
    const size_t bytes_per_slice = sizeof(float) * (colour ? 6 : 3) *
                                   static_cast<size_t>(levels[first_level].width) *
                                   levels[first_level].height;
    const int block = SliceBlockThatFits(options.slice_block, num_labels, bytes_per_slice,
                                         context->MaxAllocBytes());
    if (block < std::min(options.slice_block, num_labels)) {
      LOG_FIRST_N(INFO, 1) << "--OrientationStereo.slice_block " << options.slice_block
                           << " lowered to " << block << " so that a block's buffers fit the "
                           << "device's largest allocation (" << (context->MaxAllocBytes() >> 20)
                           << " MiB)";
    }
    // The levels used count for the paper's three (kDataTermLevelsScale), so that the data term
    // keeps its scale against lambda without the finest levels (coarse_first_level) or with
    // fewer levels (num_levels).
    const float level_weight =
        static_cast<float>(kDataTermLevelsScale) / (num_levels - first_level);
    std::vector<cl::Buffer> base_buffers, blocks;
    for (int l = 0; l < num_levels; ++l) {
      const size_t n = static_cast<size_t>(levels[l].width) * levels[l].height;
      CHECK_EQ(base[l].size(), n);
      if (l < first_level) {  // unused: no buffers
        base_buffers.emplace_back();
        blocks.emplace_back();
        continue;
      }
      base_buffers.push_back(ReadOnlyBuffer(context, base[l]));
      blocks.push_back(context->Buffer(CL_MEM_READ_WRITE, sizeof(float) * n * block));
    }
    // Selecting sources: each cost's own volume (one after another in `source_volumes`), its
    // levels summed, until the selection.
    const std::vector<LevelPipeline::Cost>& costs = levels[first_level].costs;
    const size_t num_costs = costs.size();
    cl::Buffer source_volumes;
    if (select_sources) {
      const size_t bytes = sizeof(float) * host.size() * num_costs;
      source_volumes = context->Buffer(CL_MEM_READ_WRITE, bytes);
      queue.enqueueFillBuffer(source_volumes, 0.0f, 0, bytes);
    }
    for (int s0 = 0; s0 < num_labels; s0 += block) {
      const int ns = std::min(block, num_labels - s0);
      for (int l = first_level; l < num_levels; ++l) {
        // The guided filter is linear: each cost is aggregated and added with its weight.
        for (size_t c = 0; c < levels[l].costs.size(); ++c) {
          const LevelPipeline::Cost& cost = levels[l].costs[c];
          {
            ScopedStageTimer timer(timings, "cost volume");
            cost.volume->Compute(base_buffers[l], step, s0, ns, labels, blocks[l]);
            queue.finish();
          }
          ScopedStageTimer timer(timings, "aggregation");
          levels[l].filter->Filter(blocks[l], ns, blocks[l]);
          resample.Run(blocks[l], levels[l].width, levels[l].height, ns,
                       select_sources ? source_volumes : volume, gw, gh,
                       select_sources ? static_cast<int>(c) * num_labels + s0 : s0,
                       level_weight * cost.weight,
                       static_cast<float>(LevelPixelsPerPixel(l, grid_level)));
          queue.finish();
        }
      }
    }
    if (select_sources) {
      // Each term's sources lie together in `costs` (one term after the other).
      ScopedStageTimer timer(timings, "source selection");
      for (size_t first = 0; first < num_costs;) {
        size_t end = first;
        while (end < num_costs && costs[end].term == costs[first].term) ++end;
        const int count = static_cast<int>(end - first);
        select.Run(source_volumes, static_cast<int>(first), count,
                   std::min(num_best_sources, count), host.size(), volume);
        first = end;
      }
      queue.finish();
    }
    queue.enqueueReadBuffer(volume, CL_TRUE, 0, sizeof(float) * host.size(), host.data());
    return host;
  };

  DepthEstimate estimate;
  estimate.label_step_px = LabelStepPxPerRadian(ref.camera, labels);
  estimate.lambda = options.ViewLambda(estimate.label_step_px);
  const double truncation = options.truncation_labels > 0
                                ? options.truncation_labels * options.truncation_labels
                                : std::numeric_limits<double>::infinity();
  auto solve = [&](int grid_level, int num_labels, std::vector<float>* volume,
                   std::vector<float> offset, float step, double* energy) {
    ScopedStageTimer timer(timings, "MRF");
    MrfProblem problem;
    problem.width = levels[grid_level].width;
    problem.height = levels[grid_level].height;
    problem.num_labels = num_labels;
    problem.data_cost.swap(*volume);
    problem.label_offset = std::move(offset);
    problem.label_step = step;
    problem.truncation = static_cast<float>(truncation);
    SmoothnessWeights(guide(grid_level), estimate.lambda, options.sigma_o,
                      &problem.weight_right, &problem.weight_down);
    MrfResult result = SolveMrf(problem, mrf_options, context);
    *energy = result.energy;
    problem.data_cost.swap(*volume);
    return result.labels;
  };

  const int num_depths = labels.num_labels;
  const bool two_stage = options.coarse_level > 0 && num_pyramid_levels > 1;
  const int coarse_level = two_stage ? std::min(options.coarse_level, num_pyramid_levels - 1) : 0;
  // The finest level of the coarse stage's data term: at most the grid's, and one of the
  // data term's levels.
  const int coarse_first_level =
      two_stage ? std::min({options.coarse_first_level, coarse_level, num_levels - 1}) : 0;

  // The visual hull's depth bound (its entry less the tolerance) as labels on the level-0 grid
  // (-inf = none): where the coarse labels start, and, per visual_hull_depth_bound, a bound.
  std::vector<float> bound0;
  if (!visual_hull_entry.Empty()) {
    bound0.assign(static_cast<size_t>(width0) * height0, -std::numeric_limits<float>::infinity());
    for (size_t p = 0; p < bound0.size(); ++p) {
      const float entry = visual_hull_entry.Data()[p];
      const double d = entry - options.visual_hull_tolerance_m;
      if (entry > 0 && d > 0) bound0[p] = static_cast<float>(labels.Label(d));
    }
  }
  const bool penalize =
      options.visual_hull_depth_bound == VisualHullBound::kPenalty && !bound0.empty();
  const bool filter_by_bound =
      options.visual_hull_depth_bound == VisualHullBound::kFilter && !bound0.empty();

  // Coarse stage: every label, on the coarse grid; from the visual hull's bound on with
  // coarse_labels_from_visual_hull.
  if (progress != nullptr) progress->Stage("cost volume and aggregation (all depths)");
  const bool coarse_from_hull =
      options.coarse_labels_from_visual_hull && !visual_hull_entry.Empty();
  std::vector<std::vector<float>> coarse_base(num_pyramid_levels);
  for (int l = 0; l < num_pyramid_levels; ++l) {
    coarse_base[l] = coarse_from_hull
                         ? VisualHullLabelBase(bound0, width0, height0, labels, l,
                                               levels[l].width, levels[l].height)
                         : std::vector<float>(
                               static_cast<size_t>(levels[l].width) * levels[l].height, 0.0f);
  }
  const int cw = levels[coarse_level].width, ch = levels[coarse_level].height;
  const std::vector<float>& coarse_grid_base = coarse_base[coarse_level];
  const size_t coarse_size = static_cast<size_t>(cw) * ch * num_depths;
  std::vector<float> coarse_volume;
  if (coarse_volume_cache != nullptr && coarse_volume_cache->size() == coarse_size) {
    // Moved out, not copied: the caller passes a copy where it needs the volume again.
    coarse_volume = std::move(*coarse_volume_cache);
    coarse_volume_cache->clear();
  } else {
    coarse_volume = build_volume(coarse_level, coarse_first_level, num_depths, coarse_base, 1.0f);
    if (coarse_volume_cache != nullptr) *coarse_volume_cache = coarse_volume;
  }
  const bool use_prior = prior != nullptr && !prior->views.empty() && prior->weight > 0;
  if (options.write_cost_volume && prior == nullptr) {
    CostVolume& data_term = estimate.coarse_data_term;
    data_term.cost = CostOnRangeLabels(coarse_volume, coarse_grid_base, cw, ch, num_depths);
    for (int k = 0; k < num_depths; ++k) data_term.label_depths.push_back(labels.Depth(k));
  }
  float prior_scale = 0;
  std::optional<GeometricPriorCL> prior_cl;  // the views' maps on the device, for both stages
  // Where the prior is added: the mask's pixels, and on the coarse grid every block with one.
  std::vector<uint8_t> prior_active0, prior_active_coarse;
  if (use_prior) {
    ScopedStageTimer timer(timings, "geometric prior");
    if (!mask.Empty()) {
      CHECK_EQ(mask.Width(), width0);
      CHECK_EQ(mask.Height(), height0);
      const int factor = 1 << coarse_level;
      prior_active0.resize(static_cast<size_t>(width0) * height0);
      prior_active_coarse.assign(static_cast<size_t>(cw) * ch, 0);
      for (int row = 0; row < height0; ++row) {
        for (int col = 0; col < width0; ++col) {
          const bool inside = mask.At(row, col) > 0.5f;
          prior_active0[static_cast<size_t>(row) * width0 + col] = inside;
          const int r = std::min(row / factor, ch - 1), c = std::min(col / factor, cw - 1);
          prior_active_coarse[static_cast<size_t>(r) * cw + c] |= inside;
        }
      }
    }
    prior_scale = MedianCostRange(coarse_volume, static_cast<size_t>(cw) * ch, num_depths);
    prior_cl.emplace(context, *prior);
    prior_cl->Add(ref.camera.PyramidLevel(coarse_level), LevelPixelsPerPixel(0, coarse_level),
                  labels, coarse_grid_base, 1.0f, num_depths, prior_active_coarse, prior_scale,
                  &coarse_volume);
  }
  if (penalize) {
    // On the coarse grid, the smallest bound of each block, so that it never excludes what a
    // finer pixel allows.
    const int factor = 1 << coarse_level;
    std::vector<float> bound_coarse(static_cast<size_t>(cw) * ch,
                                    -std::numeric_limits<float>::infinity());
    for (int row = 0; row < height0; ++row) {
      for (int col = 0; col < width0; ++col) {
        const float b = bound0[row * width0 + col];
        const int r = std::min(row / factor, ch - 1), c = std::min(col / factor, cw - 1);
        float& coarse = bound_coarse[r * cw + c];
        if (std::isfinite(b) && (!std::isfinite(coarse) || b < coarse)) coarse = b;
      }
    }
    PenalizeInFrontOfBound(bound_coarse, coarse_grid_base, 1.0f, num_depths, &coarse_volume);
  }
  if (progress != nullptr) progress->Stage("MRF (all depths)");
  const int coarse_pixels = cw * ch;
  const std::vector<int> coarse_labels =
      solve(coarse_level, num_depths, &coarse_volume,
            // Label values: depths (the base added) or offsets behind the hull (without it).
            coarse_from_hull && options.coarse_smoothness_along_visual_hull
                ? std::vector<float>()
                : coarse_grid_base,
            1.0f, &estimate.coarse_energy);

  FloatMap coarse_value(cw, ch, 1);
  FloatMap coarse_confidence(cw, ch, 1);
  {
    ScopedStageTimer timer(timings, "refinement");
    const std::vector<float> offsets =
        options.subpixel_refinement
            ? SubpixelOffsets(coarse_volume, coarse_pixels, num_depths, coarse_labels)
            : std::vector<float>(coarse_pixels, 0.0f);
    for (int p = 0; p < coarse_pixels; ++p) {
      coarse_value.Data()[p] = coarse_grid_base[p] + coarse_labels[p] + offsets[p];
      // Confidence: how much worse the best label at least 2 labels away is.
      const int l = coarse_labels[p];
      float other = std::numeric_limits<float>::infinity();
      for (int k = 0; k < num_depths; ++k) {
        if (std::abs(k - l) >= 2) {
          other = std::min(other, coarse_volume[static_cast<size_t>(k) * coarse_pixels + p]);
        }
      }
      const float chosen = coarse_volume[static_cast<size_t>(l) * coarse_pixels + p];
      // Clamped at 0: where the MRF chose a label that is not the data term's best, the
      // data term gives no margin for it.
      coarse_confidence.Data()[p] = std::isfinite(other) ? std::max(other - chosen, 0.0f) : 0.0f;
    }
  }
  coarse_volume.clear();
  coarse_volume.shrink_to_fit();

  FloatMap value(width0, height0, 1);
  if (two_stage) {
    // Fine stage: a band of fine labels around the upsampled coarse labels, at full size.
    const int band = options.fine_num_labels;
    const float step = static_cast<float>(options.fine_label_step);
    const float half = 0.5f * (band - 1) * step;
    const float max_base = std::max(0.0f, (num_depths - 1) - (band - 1) * step);
    std::vector<std::vector<float>> base(num_levels);
    for (int l = 0; l < num_levels; ++l) {
      const FloatMap up = ResampleBilinear(coarse_value, levels[l].width, levels[l].height,
                                           LevelPixelsPerPixel(coarse_level, l));
      base[l].resize(up.Data().size());
      for (size_t p = 0; p < base[l].size(); ++p) {
        base[l][p] = std::clamp(up.Data()[p] - half, 0.0f, max_base);
      }
    }
    if (progress != nullptr) progress->Stage("cost volume and aggregation (fine band)");
    std::vector<float> fine_volume = build_volume(0, 0, band, base, step);
    // The cost volumes' and the coarser levels' filters' device buffers are done with: freed
    // before the prior and the MRF allocate theirs, so that the device's peak is the larger of
    // the two, not their sum (level 0's filter stays for the final depth filter).
    for (size_t l = 0; l < levels.size(); ++l) {
      levels[l].costs.clear();
      if (l > 0) levels[l].filter.reset();
    }
    if (use_prior) {
      ScopedStageTimer timer(timings, "geometric prior");
      prior_cl->Add(ref.camera.Scaled(width0, height0), 1.0, labels, base[0], step, band,
                    prior_active0, prior_scale, &fine_volume);
    }
    if (penalize) {
      PenalizeInFrontOfBound(bound0, base[0], step, band, &fine_volume);
    }
    if (progress != nullptr) progress->Stage("MRF (fine band)");
    const std::vector<int> fine_labels =
        solve(0, band, &fine_volume, base[0], step, &estimate.fine_energy);
    ScopedStageTimer timer(timings, "refinement");
    const int n = width0 * height0;
    const std::vector<float> offsets = options.subpixel_refinement
                                           ? SubpixelOffsets(fine_volume, n, band, fine_labels)
                                           : std::vector<float>(n, 0.0f);
    for (int p = 0; p < n; ++p) {
      value.Data()[p] = base[0][p] + (fine_labels[p] + offsets[p]) * step;
    }
  } else {
    value = coarse_value;
  }

  if (progress != nullptr) progress->Stage("refinement");
  ScopedStageTimer timer(timings, "refinement");
  estimate.confidence = coarse_level == 0 ? coarse_confidence
                                          : ResampleBilinear(coarse_confidence, width0, height0,
                                                             LevelPixelsPerPixel(coarse_level, 0));
  FloatMap depth(width0, height0, 1);
  for (size_t p = 0; p < depth.Data().size(); ++p) {
    depth.Data()[p] = static_cast<float>(labels.Depth(value.Data()[p]));
  }
  if (options.final_guided_filter) {
    // Paper Eq. 10: the depth map filtered once more with the finest level's weights.
    depth = levels[0].filter->Filter(depth);
  }
  const FloatMap mask0 = mask.Empty() ? FloatMap(width0, height0, 1, 1.0f) : mask;
  CHECK_EQ(mask0.Width(), width0);
  CHECK_EQ(mask0.Height(), height0);
  for (size_t p = 0; p < depth.Data().size(); ++p) {
    const float v = value.Data()[p];
    const bool in_mask = mask0.Data()[p] > 0.5f;
    const bool at_range_end = v < 0.5f || v > num_depths - 1.5f;
    const bool hull_behind_range = !bound0.empty() && bound0[p] > num_depths - 1.5f;
    const bool at_far_end = v > num_depths - 1.5f || hull_behind_range;
    estimate.num_in_mask += in_mask;
    estimate.num_at_far_end += in_mask && at_far_end;
    estimate.num_at_near_end += in_mask && !at_far_end && v < 0.5f;
    bool valid = in_mask && depth.Data()[p] > 0;
    if (options.filter_range_ends && at_range_end) valid = false;
    if (filter_by_bound && v < bound0[p]) valid = false;
    if (estimate.confidence.Data()[p] < options.min_confidence) valid = false;
    if (!valid) depth.Data()[p] = 0.0f;
    if (valid) ++estimate.num_valid;
  }
  estimate.depth = std::move(depth);
  return estimate;
}

// The part of the reference's level-0 grid that the estimate needs: the mask's bounding box
// grown by `margin` px, its top-left corner a multiple of `align` = 2^(last pyramid level), so
// that every level's grid is the matching part of the whole level's (PyramidLevel: ceil(size /
// 2) per level), and its width and height multiples of kCropSizeMultiple where the image allows
// (moved back from the image's edge if need be): PoCL runs a kernel in work-groups whose size
// divides the global size, and sizes with few factors of 2 leave it small groups, which it
// vectorises less well. Empty (width 0) when the mask has no pixel.
constexpr int kCropSizeMultiple = 32;

// [start, start + size) along an axis of `length` px holding [first, last] grown by margin.
void CropAxis(int first, int last, int length, int margin, int align, int* start, int* size) {
  const int begin = std::max(0, (first - margin) / align * align);
  const int end = std::min(length, last + 1 + margin);
  const int rounded = static_cast<int>(RoundUpToMultiple(end - begin, kCropSizeMultiple));
  *start = begin;
  *size = rounded;
  if (begin + rounded > length) {  // moved back from the edge, keeping the alignment
    *start = std::max(0, (length - rounded) / align * align);
    // Up to the edge where the alignment or the image leaves less than the box.
    if (*start + rounded < end || rounded > length) *size = length - *start;
  }
}

PixelBox MaskCrop(const FloatMap& mask, int margin, int align) {
  const PixelBox box = BoundingBoxAbove(mask, 0.5f);
  PixelBox crop;
  if (box.Empty()) return crop;
  CropAxis(box.x0, box.x0 + box.width - 1, mask.Width(), margin, align, &crop.x0, &crop.width);
  CropAxis(box.y0, box.y0 + box.height - 1, mask.Height(), margin, align, &crop.y0,
           &crop.height);
  return crop;
}

// Level `level` of a pyramid (orientation fields or colours) cropped as `crop` is at level 0,
// to the size of that level of the cropped camera `part`.
FloatMap CropLevel(const FloatMap& map, const PixelBox& crop, const StereoCamera& part,
                   int level) {
  const StereoCamera grid = part.PyramidLevel(level);
  const int x0 = crop.x0 >> level, y0 = crop.y0 >> level;
  CHECK_LE(x0 + grid.width, map.Width());
  CHECK_LE(y0 + grid.height, map.Height());
  return CropFloatMap(map, x0, y0, grid.width, grid.height);
}

}  // namespace

DepthEstimate EstimateDepthMap(OpenCLContext* context, const StereoViewData& ref,
                               const std::vector<const StereoViewData*>& sources,
                               const FloatMap& mask, const FloatMap& visual_hull_entry,
                               const DepthLabels& labels,
                               const OrientationStereoOptions& options, StageTimings* timings,
                               Progress* progress, const GeometricPrior* prior,
                               std::vector<float>* coarse_volume_cache) {
  auto whole_grid = [&] {
    return EstimateDepthMapOnGrid(context, ref, sources, mask, visual_hull_entry, labels, options,
                                  timings, progress, prior, coarse_volume_cache);
  };
  if (!options.crop_to_mask || mask.Empty() || ref.orientation.empty()) return whole_grid();
  const int width0 = ref.orientation[0].Width(), height0 = ref.orientation[0].Height();
  CHECK_EQ(mask.Width(), width0);
  CHECK_EQ(mask.Height(), height0);
  const size_t num_pyramid_levels =
      std::max({ref.orientation.size(), ref.matching.size(), ref.rgb.size()});
  // Past the farthest any window reaches from a masked pixel: the aggregation's at every level
  // of the data term (in level-0 px), the final filter's (level 0's) and the colour cost's NCC
  // window; twice that, so that a window near the mask's edge sees what it saw on the whole grid.
  int reach = options.ncc_window_px / 2 + 1;
  for (size_t l = 0; l < std::min<size_t>(num_pyramid_levels, options.num_levels); ++l) {
    reach = std::max(reach, (options.WindowPx(static_cast<int>(l)) / 2 + 1) << l);
  }
  const PixelBox crop = MaskCrop(mask, 2 * reach, 1 << (num_pyramid_levels - 1));
  if (crop.width == 0 || (crop.width == width0 && crop.height == height0)) return whole_grid();

  StereoViewData part;
  part.camera = ref.camera;
  part.camera.K(0, 2) -= crop.x0;
  part.camera.K(1, 2) -= crop.y0;
  part.camera.width = crop.width;
  part.camera.height = crop.height;
  auto crop_pyramid = [&](const std::vector<FloatMap>& pyramid) {
    std::vector<FloatMap> levels;
    for (size_t l = 0; l < pyramid.size(); ++l) {
      levels.push_back(CropLevel(pyramid[l], crop, part.camera, static_cast<int>(l)));
    }
    return levels;
  };
  part.orientation = crop_pyramid(ref.orientation);
  part.matching = crop_pyramid(ref.matching);
  part.rgb = crop_pyramid(ref.rgb);
  const FloatMap part_mask = CropLevel(mask, crop, part.camera, 0);
  const FloatMap part_hull =
      visual_hull_entry.Empty() ? FloatMap() : CropLevel(visual_hull_entry, crop, part.camera, 0);
  DepthEstimate estimate =
      EstimateDepthMapOnGrid(context, part, sources, part_mask, part_hull, labels, options,
                             timings, progress, prior, coarse_volume_cache);
  // Back onto the whole grid: nothing outside the crop (the mask's zeros, as on the whole grid).
  estimate.depth = UncropFloatMap(estimate.depth, crop.x0, crop.y0, width0, height0);
  estimate.confidence = UncropFloatMap(estimate.confidence, crop.x0, crop.y0, width0, height0);
  FloatMap& data_term = estimate.coarse_data_term.cost;
  if (!data_term.Empty()) {
    int level = 0;
    StereoCamera whole = ref.camera;
    for (StereoCamera grid = part.camera; grid.width != data_term.Width(); ++level) {
      CHECK_LT(level, 16);
      grid = grid.PyramidLevel(1);
      whole = whole.PyramidLevel(1);
    }
    FloatMap whole_term(whole.width, whole.height, data_term.Channels());
    PasteFloatMap(data_term, crop.x0 >> level, crop.y0 >> level, &whole_term);
    data_term = std::move(whole_term);
  }
  return estimate;
}

}  // namespace hairmvs
