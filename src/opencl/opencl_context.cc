#include "src/opencl/opencl_context.h"

#include <algorithm>
#include <limits>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iomanip>
#include <set>
#include <new>
#include <sstream>

#include "kernels/embedded_kernels.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/opencl/opencl_error.h"

namespace hairmvs {
namespace {

std::string DeviceTypeName(cl_device_type type) {
  if (type & CL_DEVICE_TYPE_GPU) return "GPU";
  if (type & CL_DEVICE_TYPE_CPU) return "CPU";
  if (type & CL_DEVICE_TYPE_ACCELERATOR) return "ACCELERATOR";
  return "OTHER";
}

// Platform/device pairs in a fixed order: platforms as the ICD loader lists them, devices as
// each platform lists them. Throws when no platform exists.
std::vector<std::pair<cl::Platform, cl::Device>> AllDevices() {
  std::vector<cl::Platform> platforms;
  cl_int err = CL_SUCCESS;
  try {
    err = cl::Platform::get(&platforms);
  } catch (const cl::Error& e) {
    err = e.err();
  }
  THROW_IF(err != CL_SUCCESS || platforms.empty(),
           "No OpenCL platform found (" << OpenCLErrorString(err)
                                        << "). Install an OpenCL driver, e.g. the Debian package "
                                           "pocl-opencl-icd (a CPU implementation), and check "
                                           "that /etc/OpenCL/vendors/ lists an .icd file.");
  std::vector<std::pair<cl::Platform, cl::Device>> result;
  for (auto& platform : platforms) {
    std::vector<cl::Device> devices;
    try {
      platform.getDevices(CL_DEVICE_TYPE_ALL, &devices);
    } catch (const cl::Error&) {
      continue;  // CL_DEVICE_NOT_FOUND: a platform without devices.
    }
    for (auto& device : devices) result.emplace_back(platform, device);
  }
  THROW_IF(result.empty(), "OpenCL platforms exist but expose no device. Install an OpenCL "
                           "driver, e.g. the Debian package pocl-opencl-icd.");
  return result;
}

OpenCLDeviceInfo DescribeDevice(int index, const cl::Platform& platform, const cl::Device& device) {
  OpenCLDeviceInfo info;
  info.index = index;
  info.platform_name = StripWhitespace(platform.getInfo<CL_PLATFORM_NAME>());
  info.device_name = StripWhitespace(device.getInfo<CL_DEVICE_NAME>());
  info.type = DeviceTypeName(device.getInfo<CL_DEVICE_TYPE>());
  info.compute_units = static_cast<int>(device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>());
  info.global_memory_mib = device.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>() / (1024.0 * 1024.0);
  info.max_alloc_mib = device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>() / (1024.0 * 1024.0);
  info.local_memory_kib = device.getInfo<CL_DEVICE_LOCAL_MEM_SIZE>() / 1024.0;
  info.max_work_group_size = device.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>();
  info.opencl_c_version = StripWhitespace(device.getInfo<CL_DEVICE_OPENCL_C_VERSION>());
  info.device_version = StripWhitespace(device.getInfo<CL_DEVICE_VERSION>());
  return info;
}

bool IsNumber(const std::string& s) {
  return !s.empty() &&
         std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

void ResolveIncludesInText(const std::string& file, const std::string& text,
                           std::set<std::string>* included, std::ostream& out);

void ResolveIncludes(const std::string& file, std::set<std::string>* included, std::ostream& out) {
  const auto& sources = EmbeddedKernelSources();
  const auto it = sources.find(file);
  if (it == sources.end()) {
    std::ostringstream known;
    for (const auto& [name, text] : sources) known << " " << name;
    HAIRMVS_THROW("Unknown OpenCL kernel file '" << file << "' (embedded kernels:" << known.str()
                                                 << ")");
  }
  if (!included->insert(file).second) return;
  ResolveIncludesInText(file, it->second, included, out);
}

void ResolveIncludesInText(const std::string& file, const std::string& text,
                           std::set<std::string>* included, std::ostream& out) {
  std::istringstream in(text);
  std::string line;
  int line_number = 0;
  out << "#line 1 \"" << file << "\"\n";
  while (std::getline(in, line)) {
    ++line_number;
    const std::string stripped = StripWhitespace(line);
    if (stripped.rfind("#include", 0) == 0) {
      const size_t open = stripped.find('"');
      const size_t close = stripped.rfind('"');
      THROW_IF(open == std::string::npos || close <= open,
               "Kernel file '" << file << "' line " << line_number
                               << ": only #include \"name.clh\" is supported, got: " << stripped);
      ResolveIncludes(stripped.substr(open + 1, close - open - 1), included, out);
      out << "#line " << line_number + 1 << " \"" << file << "\"\n";
      continue;
    }
    out << line << "\n";
  }
}

}  // namespace

// What to do when the device is out of memory: the end of both messages that say so.
constexpr const char* kOpenCLOutOfMemoryAdvice =
    "smaller images (--OrientationStereo.max_image_size; orientation_fields' --max_image_size), "
    "fewer labels (--OrientationStereo.num_depths, fine_num_labels: the cost volumes grow with "
    "them), fewer depth slices per block on the device (--OrientationStereo.slice_block: the "
    "guided filter's and the colour cost's largest buffers grow with it), or --OpenCL.device of "
    "another device (`hairmvs opencl_devices` lists each device's memory and largest "
    "allocation)";

// What to do when the host's memory ran out (std::bad_alloc).
constexpr const char* kHostOutOfMemoryAdvice =
    "smaller images (--OrientationStereo.max_image_size), fewer labels "
    "(--OrientationStereo.num_depths), a smaller --OrientationStereo.coarse_volume_cache_mib, or "
    "fewer views per process (--image_names; README, \"Splitting the work on a cluster\")";

std::string DescribeException(const std::exception& e) {
  if (dynamic_cast<const std::bad_alloc*>(&e) != nullptr) {
    return std::string("out of host memory (") + e.what() + "); " + kHostOutOfMemoryAdvice;
  }
  const auto* error = dynamic_cast<const cl::Error*>(&e);
  if (error == nullptr) return e.what();
  std::ostringstream message;
  message << "OpenCL call " << error->what() << " failed: " << OpenCLErrorString(error->err());
  switch (error->err()) {
    case CL_MEM_OBJECT_ALLOCATION_FAILURE:
    case CL_OUT_OF_HOST_MEMORY:
    case CL_INVALID_BUFFER_SIZE:
      message << ": the device ran out of memory, or a buffer exceeds its largest allocation; "
              << kOpenCLOutOfMemoryAdvice;
      break;
    case CL_OUT_OF_RESOURCES:
      // GPU drivers (NVIDIA's) also report a kernel that failed (an access out of bounds) or
      // was stopped by the display's watchdog so.
      message << ": the device ran out of memory or other resources, or a kernel failed or "
                 "was stopped (a GPU that also drives a display stops long kernels); if memory, "
              << kOpenCLOutOfMemoryAdvice;
      break;
    default:
      break;
  }
  return message.str();
}

std::string DescribeExceptionWithin(const std::string& item, const std::string& where,
                                    const std::exception& e) {
  const std::string message = DescribeException(e);
  return message.rfind(item + ":", 0) == 0 ? message : where + ": " + message;
}

std::string OpenCLErrorString(cl_int code) {
  const char* name = "unknown error";
  switch (code) {
#define X(CODE)    \
  case CODE:       \
    name = #CODE;  \
    break;
    // Every code of OpenCL 1.2's cl.h.
    X(CL_SUCCESS)
    X(CL_DEVICE_NOT_FOUND)
    X(CL_DEVICE_NOT_AVAILABLE)
    X(CL_COMPILER_NOT_AVAILABLE)
    X(CL_MEM_OBJECT_ALLOCATION_FAILURE)
    X(CL_OUT_OF_RESOURCES)
    X(CL_OUT_OF_HOST_MEMORY)
    X(CL_PROFILING_INFO_NOT_AVAILABLE)
    X(CL_MEM_COPY_OVERLAP)
    X(CL_IMAGE_FORMAT_MISMATCH)
    X(CL_IMAGE_FORMAT_NOT_SUPPORTED)
    X(CL_BUILD_PROGRAM_FAILURE)
    X(CL_MAP_FAILURE)
    X(CL_MISALIGNED_SUB_BUFFER_OFFSET)
    X(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
    X(CL_COMPILE_PROGRAM_FAILURE)
    X(CL_LINKER_NOT_AVAILABLE)
    X(CL_LINK_PROGRAM_FAILURE)
    X(CL_DEVICE_PARTITION_FAILED)
    X(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
    X(CL_INVALID_VALUE)
    X(CL_INVALID_DEVICE_TYPE)
    X(CL_INVALID_PLATFORM)
    X(CL_INVALID_DEVICE)
    X(CL_INVALID_CONTEXT)
    X(CL_INVALID_QUEUE_PROPERTIES)
    X(CL_INVALID_COMMAND_QUEUE)
    X(CL_INVALID_HOST_PTR)
    X(CL_INVALID_MEM_OBJECT)
    X(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
    X(CL_INVALID_IMAGE_SIZE)
    X(CL_INVALID_SAMPLER)
    X(CL_INVALID_BINARY)
    X(CL_INVALID_BUILD_OPTIONS)
    X(CL_INVALID_PROGRAM)
    X(CL_INVALID_PROGRAM_EXECUTABLE)
    X(CL_INVALID_KERNEL_NAME)
    X(CL_INVALID_KERNEL_DEFINITION)
    X(CL_INVALID_KERNEL)
    X(CL_INVALID_ARG_INDEX)
    X(CL_INVALID_ARG_VALUE)
    X(CL_INVALID_ARG_SIZE)
    X(CL_INVALID_KERNEL_ARGS)
    X(CL_INVALID_WORK_DIMENSION)
    X(CL_INVALID_WORK_GROUP_SIZE)
    X(CL_INVALID_WORK_ITEM_SIZE)
    X(CL_INVALID_GLOBAL_OFFSET)
    X(CL_INVALID_EVENT_WAIT_LIST)
    X(CL_INVALID_EVENT)
    X(CL_INVALID_OPERATION)
    X(CL_INVALID_GL_OBJECT)
    X(CL_INVALID_BUFFER_SIZE)
    X(CL_INVALID_MIP_LEVEL)
    X(CL_INVALID_GLOBAL_WORK_SIZE)
    X(CL_INVALID_PROPERTY)
    X(CL_INVALID_IMAGE_DESCRIPTOR)
    X(CL_INVALID_COMPILER_OPTIONS)
    X(CL_INVALID_LINKER_OPTIONS)
    X(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef X
    case -1001: name = "CL_PLATFORM_NOT_FOUND_KHR (no OpenCL driver installed)"; break;
    case -9999: name = "NVIDIA driver error (a kernel's access out of bounds?)"; break;
    default: break;
  }
  return std::string(name) + " (" + std::to_string(code) + ")";
}

std::vector<OpenCLDeviceInfo> ListOpenCLDevices() {
  std::vector<OpenCLDeviceInfo> infos;
  const auto devices = AllDevices();
  for (size_t i = 0; i < devices.size(); ++i) {
    infos.push_back(DescribeDevice(static_cast<int>(i), devices[i].first, devices[i].second));
  }
  return infos;
}

std::string OpenCLDevicesTable(const std::vector<OpenCLDeviceInfo>& devices) {
  std::ostringstream out;
  char line[512];
  std::snprintf(line, sizeof(line), "%-5s %-11s %-6s %10s %10s %9s %-22s %s\n", "index", "type",
                "CUs", "mem MiB", "alloc MiB", "local KiB", "OpenCL C", "platform / device");
  out << line;
  for (const auto& d : devices) {
    std::snprintf(line, sizeof(line), "%-5d %-11s %-6d %10.0f %10.0f %9.0f %-22s %s / %s\n",
                  d.index, d.type.c_str(), d.compute_units, d.global_memory_mib, d.max_alloc_mib,
                  d.local_memory_kib, d.opencl_c_version.c_str(), d.platform_name.c_str(),
                  d.device_name.c_str());
    out << line;
  }
  return out.str();
}

std::shared_ptr<OpenCLContext> OpenCLContext::Create(const std::string& device_spec) {
  const auto devices = AllDevices();
  const std::string spec = StripWhitespace(device_spec);
  int chosen = -1;
  if (spec.empty()) {
    for (size_t i = 0; i < devices.size() && chosen < 0; ++i) {
      if (devices[i].second.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_GPU) {
        chosen = static_cast<int>(i);
      }
    }
    for (size_t i = 0; i < devices.size() && chosen < 0; ++i) {
      if (devices[i].second.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_CPU) {
        chosen = static_cast<int>(i);
      }
    }
    if (chosen < 0) chosen = 0;
  } else if (IsNumber(spec)) {
    // More digits than any device count has: out of range, not a std::stol overflow.
    const long index = spec.size() > 9 ? std::numeric_limits<long>::max() : std::stol(spec);
    THROW_IF(index >= static_cast<long>(devices.size()),
             "--OpenCL.device " << spec << ": no such device index; there are " << devices.size()
                                << " device(s):\n"
                                << OpenCLDevicesTable(ListOpenCLDevices()));
    chosen = static_cast<int>(index);
  } else {
    const std::string needle = ToLower(spec);
    for (size_t i = 0; i < devices.size() && chosen < 0; ++i) {
      const std::string name =
          ToLower(StripWhitespace(devices[i].first.getInfo<CL_PLATFORM_NAME>()) + " / " +
                  StripWhitespace(devices[i].second.getInfo<CL_DEVICE_NAME>()));
      if (name.find(needle) != std::string::npos) chosen = static_cast<int>(i);
    }
    THROW_IF(chosen < 0, "--OpenCL.device '" << spec
                                             << "': no device index or name matches; devices:\n"
                                             << OpenCLDevicesTable(ListOpenCLDevices()));
  }

  std::shared_ptr<OpenCLContext> ctx(new OpenCLContext());
  const auto& [platform, device] = devices[chosen];
  ctx->device_ = device;
  ctx->platform_name_ = StripWhitespace(platform.getInfo<CL_PLATFORM_NAME>());
  ctx->device_name_ = StripWhitespace(device.getInfo<CL_DEVICE_NAME>());
  ctx->is_cpu_ = (device.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_CPU) != 0;
  ctx->max_alloc_bytes_ = static_cast<size_t>(device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>());
  try {
    ctx->context_ = cl::Context(device);
    ctx->queue_ = cl::CommandQueue(ctx->context_, device);  // in-order, no profiling
  } catch (const cl::Error& e) {
    HAIRMVS_THROW("Could not create an OpenCL context on '" << ctx->device_name_ << "': "
                                                             << e.what() << " "
                                                             << OpenCLErrorString(e.err()));
  }
  return ctx;
}

std::string ResolveKernelSource(const std::string& file) {
  std::set<std::string> included;
  std::ostringstream out;
  ResolveIncludes(file, &included, out);
  return out.str();
}

cl::Program& OpenCLContext::Program(const std::vector<std::string>& kernel_files,
                                    const std::string& build_options) {
  CHECK(!kernel_files.empty());
  std::set<std::string> included;
  std::ostringstream source;
  for (const auto& file : kernel_files) ResolveIncludes(file, &included, source);
  return BuildProgram(source.str(), build_options);
}

cl::Program& OpenCLContext::ProgramFromSource(const std::string& text,
                                              const std::string& build_options) {
  std::set<std::string> included;
  std::ostringstream resolved;
  ResolveIncludesInText("<source>", text, &included, resolved);
  return BuildProgram(resolved.str(), build_options);
}

cl::Program& OpenCLContext::BuildProgram(const std::string& source,
                                         const std::string& build_options) {
  std::lock_guard<std::mutex> lock(program_mutex_);
  const std::string key = source + "\n//options: " + build_options;
  const auto it = programs_.find(key);
  if (it != programs_.end()) return it->second;

  cl::Program program(context_, source);
  // -cl-std=CL1.2: the kernels are OpenCL C 1.2 whatever the device's newest version. Where
  // the device can, divisions and square roots are correctly rounded, as on the host: OpenCL
  // allows 2.5 ulp otherwise (many GPUs' default), and the MRF kernels are meant to give the
  // CPU reference's labels exactly (a parabola crossing an ulp off can flip a near tie).
  std::string options = "-cl-std=CL1.2 " + build_options;
  if (device_.getInfo<CL_DEVICE_SINGLE_FP_CONFIG>() & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) {
    options += " -cl-fp32-correctly-rounded-divide-sqrt";
  }
  try {
    program.build(std::vector<cl::Device>{device_}, options.c_str());
  } catch (const cl::Error& e) {
    std::string log;
    try {
      log = program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(device_);
    } catch (const cl::Error&) {
      log = "(no build log)";
    }
    // Name the first line of the source, which says which kernel file failed.
    HAIRMVS_THROW("OpenCL program build failed on '" << device_name_ << "' ("
                                                      << OpenCLErrorString(e.err())
                                                      << ", options '" << options << "', source "
                                                      << source.substr(0, source.find('\n'))
                                                      << "). Build log:\n"
                                                      << log);
  }
  return programs_.emplace(key, std::move(program)).first->second;
}

cl::Buffer OpenCLContext::Buffer(cl_mem_flags flags, size_t bytes, void* host) const {
  constexpr double kMiB = 1024.0 * 1024.0;
  THROW_IF(bytes > max_alloc_bytes_,
           "A buffer of " << std::fixed << std::setprecision(1) << bytes / kMiB << " MiB ("
                          << bytes << " bytes) exceeds the largest allocation of OpenCL device '"
                          << device_name_ << "', " << max_alloc_bytes_ / kMiB << " MiB; "
                          << kOpenCLOutOfMemoryAdvice);
  return cl::Buffer(context_, flags, bytes, host);
}

cl::Buffer ReadOnlyBuffer(OpenCLContext* context, const void* data, size_t bytes) {
  // A buffer of 0 bytes is invalid: short data (an empty vector, whose data() may be null, or
  // a single byte) is copied from a zero-padded block of the minimum size, not read beyond.
  constexpr size_t kMinBytes = 4;
  if (bytes < kMinBytes) {
    unsigned char padded[kMinBytes] = {};
    if (bytes > 0) std::memcpy(padded, data, bytes);
    return context->Buffer(CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, kMinBytes, padded);
  }
  return context->Buffer(CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(data));
}

std::array<int, 4> ConcatenatedPlaneDims(int width, int height, size_t offset) {
  const uint64_t offset64 = offset;
  return {width, height, static_cast<int>(static_cast<uint32_t>(offset64 & 0xffffffffu)),
          static_cast<int>(static_cast<uint32_t>(offset64 >> 32))};
}

}  // namespace hairmvs
