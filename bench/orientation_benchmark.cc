// Orientation field on the OpenCL device (PoCL here): all levels of a 1404 x 936 image (the
// paper's image size), for several kernel configurations, and the kernel alone per level.
//   ./build/bench/orientation_benchmark [--benchmark_filter=...]
// Counters: Mpixel/s over all levels' pixels; GMAC/s = multiply-adds actually executed
// (tap pairs x angles-per-block x pixels, including the zero weights of the block unions).

#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <cmath>
#include <random>

#include "src/opencl/opencl_context.h"
#include "src/orientation/orientation_field.h"

namespace hairmvs {
namespace {

FloatMap BenchImage(int w, int h) {
  // Bright wavy strands on a darker, noisy background.
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> noise(-0.05f, 0.05f);
  FloatMap image(w, h, 1);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const double across = row + 12.0 * std::sin(col / 60.0) + 0.2 * col;
      const double d = across - 6.0 * std::round(across / 6.0);
      image.At(row, col) = static_cast<float>(0.2 + 0.6 * std::exp(-d * d / 1.2) + noise(rng));
    }
  }
  return image;
}

// CPU seconds of this process, PoCL's worker threads included: on a shared machine this is
// steadier than wall time (wall ~= cpu / cores when the cores are free).
double ProcessCpuSeconds() {
  rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
         1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

std::shared_ptr<OpenCLContext>& Context() {
  static std::shared_ptr<OpenCLContext> context = OpenCLContext::Create();
  return context;
}

void BM_OrientationFieldAllLevels(benchmark::State& state) {
  const int w = 1404, h = 936;
  OrientationKernelConfig config;
  config.vector_width = static_cast<int>(state.range(0));
  config.block_size = static_cast<int>(state.range(1));
  config.local_size_x = static_cast<int>(state.range(2));
  config.local_size_y = static_cast<int>(state.range(3));
  const OrientationFieldOptions options;
  OrientationFieldComputer computer(Context(), options, config);
  const FloatMap gray = BenchImage(w, h);
  computer.Compute(gray, FloatMap());  // warm-up: allocations, first-run specialisation
  StageTimings timings;
  computer.SetTimings(&timings);
  double pixels = 0;
  const double cpu_start = ProcessCpuSeconds();
  for (auto _ : state) {
    const auto levels = computer.Compute(gray, FloatMap());
    for (const auto& level : levels) pixels += level.NumPixels();
    benchmark::DoNotOptimize(levels.data());
  }
  const BlockedFilterBank blocked = MakeBlockedFilterBank(computer.Bank(), config.block_size);
  const double macs_per_pixel = static_cast<double>(blocked.weights.size());
  state.counters["Mpixel/s"] = benchmark::Counter(pixels * 1e-6, benchmark::Counter::kIsRate);
  state.counters["GMAC/s"] =
      benchmark::Counter(pixels * macs_per_pixel * 1e-9, benchmark::Counter::kIsRate);
  state.counters["cpu_s"] = (ProcessCpuSeconds() - cpu_start) / state.iterations();
  state.counters["kernel_s"] = timings.Get("filter kernel") / state.iterations();
  state.counters["upload_s"] = timings.Get("upload") / state.iterations();
  state.counters["download_s"] = timings.Get("download") / state.iterations();
  state.counters["downsample_s"] = timings.Get("downsample") / state.iterations();
  state.SetLabel(Context()->DeviceName());
}
BENCHMARK(BM_OrientationFieldAllLevels)
    ->ArgNames({"vec", "block", "lx", "ly"})
    ->Args({16, 12, 4, 4})
    ->Args({16, 9, 4, 4})
    ->Args({16, 15, 4, 4})
    ->Args({8, 12, 4, 4})
    ->Args({16, 12, 1, 1})
    ->Args({16, 12, 8, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(0.5);

}  // namespace
}  // namespace hairmvs

BENCHMARK_MAIN();
