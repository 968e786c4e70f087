#pragma once
// The OpenCL runtime of hairmvs: one device, one context, one in-order command queue, and a
// cache of programs built from the embedded kernels/ sources.
//
// Contract:
//  - Device choice (Create's device_spec): "" = the first GPU of any platform, else the first
//    CPU device; a decimal number = that index in the flat list that ListOpenCLDevices()
//    returns (and `hairmvs opencl_devices` prints); anything else = the first device whose
//    name, or "platform name / device name", contains it (case-insensitive). No platform, or
//    no matching device, throws hairmvs::Error naming the problem and what is installed.
//  - Queue(): ONE in-order queue (no out-of-order execution, no profiling). Commands run in
//    the order they are enqueued, so a kernel may use the output of the previous one without
//    events; a host read with blocking=CL_TRUE waits for everything enqueued before it.
//  - Buffers: made with Buffer() (or ReadOnlyBuffer below), which names a buffer larger than the
//    device's largest allocation before asking for it. Whoever creates a cl::Buffer owns it (cl::
//    objects are reference counted; keep them as members of the class that uses them and reuse
//    them across images). The context only owns the context, the queue and the program cache.
//  - Thread-safety: Program() is thread-safe (a mutex guards the cache). Everything else
//    (enqueueing on Queue(), setting kernel arguments) is NOT synchronised: use one context
//    per thread, or serialise the callers. cl::Kernel objects are not shareable between
//    threads that set arguments concurrently: create one per user from Program().
//  - Errors: OpenCL API failures surface as cl::Error (CL_HPP_ENABLE_EXCEPTIONS); a failed
//    program build throws hairmvs::Error with the device's build log.

#include <array>
#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "src/opencl/opencl.h"

namespace hairmvs {

// One entry per (platform, device), in the order Create() indexes them.
struct OpenCLDeviceInfo {
  int index = 0;
  std::string platform_name;
  std::string device_name;
  std::string type;  // "GPU", "CPU", "ACCELERATOR", "OTHER"
  int compute_units = 0;
  double global_memory_mib = 0;
  double max_alloc_mib = 0;
  double local_memory_kib = 0;
  size_t max_work_group_size = 0;
  std::string opencl_c_version;  // e.g. "OpenCL C 1.2 pocl"
  std::string device_version;    // e.g. "OpenCL 3.0 PoCL ..."
};

// Every device of every platform. Throws hairmvs::Error if no OpenCL platform is installed.
std::vector<OpenCLDeviceInfo> ListOpenCLDevices();
// A table of ListOpenCLDevices(), for `hairmvs opencl_devices`.
std::string OpenCLDevicesTable(const std::vector<OpenCLDeviceInfo>& devices);

class OpenCLContext {
 public:
  // See the contract above for device_spec.
  static std::shared_ptr<OpenCLContext> Create(const std::string& device_spec = "");

  cl::Context& Context() { return context_; }
  cl::CommandQueue& Queue() { return queue_; }
  cl::Device& Device() { return device_; }
  std::string DeviceName() const { return device_name_; }
  std::string PlatformName() const { return platform_name_; }
  bool IsCpu() const { return is_cpu_; }
  // CL_DEVICE_MAX_MEM_ALLOC_SIZE: the largest buffer the device allocates.
  size_t MaxAllocBytes() const { return max_alloc_bytes_; }

  // A buffer of `bytes` bytes in this context (`host`: the CL_MEM_*_HOST_PTR memory, if the flags
  // name one). Throws hairmvs::Error naming the size, the device and its limit when `bytes`
  // exceeds MaxAllocBytes(): drivers answer that with CL_INVALID_BUFFER_SIZE, or only fail at the
  // first kernel that touches the buffer, and neither says which buffer or by how much.
  cl::Buffer Buffer(cl_mem_flags flags, size_t bytes, void* host = nullptr) const;

  // The program built from the named files of kernels/ (concatenated in order; `#include
  // "x.clh"` lines resolved from the embedded sources, each file at most once), for this
  // device, with `build_options` (e.g. "-D TILE=16"). Cached by sources and options: the
  // second call is free. Throws hairmvs::Error with the build log on a build failure, or
  // naming the file when a kernel file is unknown.
  cl::Program& Program(const std::vector<std::string>& kernel_files,
                       const std::string& build_options = "");

  // Same, for source text given directly (tests, tools); its `#include "x.clh"` lines are
  // resolved from the embedded kernels too.
  cl::Program& ProgramFromSource(const std::string& source, const std::string& build_options = "");

 private:
  OpenCLContext() = default;
  cl::Program& BuildProgram(const std::string& resolved_source, const std::string& build_options);

  cl::Context context_;
  cl::Device device_;
  cl::CommandQueue queue_;
  std::string device_name_;
  std::string platform_name_;
  bool is_cpu_ = false;
  size_t max_alloc_bytes_ = 0;

  std::mutex program_mutex_;
  // Keyed by full source text + "\n//options: " + options. std::map keeps references stable.
  std::map<std::string, cl::Program> programs_;
};

// A read-only device buffer holding a copy of `bytes` bytes at `data` (at least 4 bytes, so that
// an empty array still gives a valid kernel argument).
cl::Buffer ReadOnlyBuffer(OpenCLContext* context, const void* data, size_t bytes);
// The same for the elements of a contiguous container (std::vector, std::array).
template <typename Container>
cl::Buffer ReadOnlyBuffer(OpenCLContext* context, const Container& host) {
  return ReadOnlyBuffer(context, host.data(), sizeof(*host.data()) * host.size());
}

// The four ints with which a kernel finds one of several planes concatenated into one buffer:
// width, height, and the plane's offset in elements as its low and high 32 bits (read by
// hm_plane_offset in kernels/common.clh). One int would wrap past 2^31 elements, e.g. at 45
// source fields of 6000 x 4000 (2 floats a pixel) on a device that allocates that much.
std::array<int, 4> ConcatenatedPlaneDims(int width, int height, size_t offset);

// How many groups of `size` hold `count` items: e.g. the work-items of a kernel that takes
// `size` pixels or depth slices each.
inline size_t DivideRoundingUp(size_t count, size_t size) { return (count + size - 1) / size; }

// `count` rounded up to a multiple of `local`: the global size of a launch in work-groups of
// `local` work-items, whose kernel checks its bounds. Without a local size PoCL takes a
// work-group size that divides the global size, and a size with few factors of two leaves it
// small groups that it vectorises badly (the guided filter on a 1397 x 931 image took 44% longer
// per pixel than on 1408 x 928).
inline size_t RoundUpToMultiple(size_t count, size_t local) {
  return DivideRoundingUp(count, local) * local;
}

// The text of `file` from the embedded kernels, with `#include "x.clh"` lines replaced by the
// included file (recursively, each at most once). Throws hairmvs::Error for an unknown file.
std::string ResolveKernelSource(const std::string& file);

}  // namespace hairmvs
