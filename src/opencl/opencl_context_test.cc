#include "src/opencl/opencl_context.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include "src/core/logging.h"
#include "src/core/test_util.h"
#include "src/opencl/opencl_error.h"
#include "src/opencl/opencl_options.h"

namespace hairmvs {
namespace {

// A trivial kernel that uses the embedded helper header: out[i] = in[clamp(i+shift)] * 2.
constexpr char kShiftKernel[] = R"cl(
#include "common.clh"
__kernel void shift_double(__global const float* in, __global float* out, int n, int shift) {
  const int i = get_global_id(0);
  if (i < n) out[i] = 2.0f * in[hm_clamp_index(i + shift, n)];
}
)cl";

TEST(OpenCLContext, BuildsAndRunsATrivialKernel) {
  auto context = OpenCLContext::Create();
  ASSERT_NE(context, nullptr);
  EXPECT_FALSE(context->DeviceName().empty());
  const int n = 1000;
  std::vector<float> in(n), out(n, -1.0f);
  for (int i = 0; i < n; ++i) in[i] = 0.5f * i;
  cl::Buffer in_buf(context->Context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(float),
                    in.data());
  cl::Buffer out_buf(context->Context(), CL_MEM_WRITE_ONLY, n * sizeof(float));
  cl::Kernel kernel(context->ProgramFromSource(kShiftKernel), "shift_double");
  kernel.setArg(0, in_buf);
  kernel.setArg(1, out_buf);
  kernel.setArg(2, n);
  kernel.setArg(3, 3);
  context->Queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(1024));
  context->Queue().enqueueReadBuffer(out_buf, CL_TRUE, 0, n * sizeof(float), out.data());
  for (int i = 0; i < n; ++i) {
    const int j = std::min(i + 3, n - 1);
    ASSERT_EQ(out[i], 2.0f * in[j]) << "i=" << i;
  }
}

// The kernels find each of several concatenated planes at the offset the host packed, also past
// 2^31 and 2^32 elements, which one int would wrap (no buffer that large is needed to check it).
constexpr char kPlaneOffsetKernel[] = R"cl(
#include "common.clh"
__kernel void plane_offsets(__global const int* dims, __global ulong* out) {
  const int j = get_global_id(0);
  out[j] = (ulong)hm_plane_offset(dims + 4 * j);
}
)cl";

TEST(OpenCLContext, ConcatenatedPlaneOffsetsPastTwoToThe31) {
  auto context = OpenCLContext::Create();
  const std::vector<size_t> offsets = {0, 123, (size_t{1} << 31) + 5, (size_t{1} << 32) + 7,
                                       size_t{45} * 6000 * 4000 * 2};
  std::vector<int> dims;
  for (size_t k = 0; k < offsets.size(); ++k) {
    const std::array<int, 4> plane = ConcatenatedPlaneDims(6000 + static_cast<int>(k), 4000,
                                                           offsets[k]);
    EXPECT_EQ(plane[0], 6000 + static_cast<int>(k));
    EXPECT_EQ(plane[1], 4000);
    dims.insert(dims.end(), plane.begin(), plane.end());
  }
  const cl::Buffer dims_buf = ReadOnlyBuffer(context.get(), dims);
  cl::Buffer out_buf(context->Context(), CL_MEM_WRITE_ONLY, offsets.size() * sizeof(cl_ulong));
  cl::Kernel kernel(context->ProgramFromSource(kPlaneOffsetKernel), "plane_offsets");
  kernel.setArg(0, dims_buf);
  kernel.setArg(1, out_buf);
  context->Queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(offsets.size()));
  std::vector<cl_ulong> out(offsets.size());
  context->Queue().enqueueReadBuffer(out_buf, CL_TRUE, 0, out.size() * sizeof(cl_ulong),
                                     out.data());
  for (size_t k = 0; k < offsets.size(); ++k) EXPECT_EQ(out[k], offsets[k]) << "plane " << k;
}

TEST(OpenCLContext, CachesPrograms) {
  auto context = OpenCLContext::Create();
  cl::Program& a = context->ProgramFromSource(kShiftKernel, "-D FOO=1");
  cl::Program& b = context->ProgramFromSource(kShiftKernel, "-D FOO=1");
  cl::Program& c = context->ProgramFromSource(kShiftKernel, "-D FOO=2");
  EXPECT_EQ(&a, &b);
  EXPECT_NE(&a, &c);
}

TEST(OpenCLContext, EmbeddedFilesBuild) {
  auto context = OpenCLContext::Create();
  EXPECT_NO_THROW(context->Program({"common.clh"}));
  EXPECT_THROW(context->Program({"no_such_file.cl"}), Error);
}

TEST(OpenCLContext, BuildFailureThrowsWithLog) {
  auto context = OpenCLContext::Create();
  try {
    context->ProgramFromSource(
        "__kernel void broken(__global float* x) { x[0] = undefined_name; }");
    FAIL() << "expected a build failure";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("build failed"), std::string::npos) << what;
    EXPECT_NE(what.find("undefined_name"), std::string::npos) << what;
    // Divisions are correctly rounded where the device can, as on the host.
    const bool correctly_rounded = context->Device().getInfo<CL_DEVICE_SINGLE_FP_CONFIG>() &
                                   CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT;
    EXPECT_EQ(what.find("-cl-fp32-correctly-rounded-divide-sqrt") != std::string::npos,
              correctly_rounded)
        << what;
  }
}

// A failed OpenCL call is described by its code, with what to do when memory ran out; other
// exceptions by their message.
TEST(OpenCLContext, FailedCallsAreDescribed) {
  auto context = OpenCLContext::Create();
  // A buffer of 0 bytes: every driver must refuse it with CL_INVALID_BUFFER_SIZE (one beyond
  // the largest allocation is not refused by every GPU driver, and would take its memory).
  try {
    cl::Buffer empty(context->Context(), CL_MEM_READ_WRITE, 0);
    ADD_FAILURE() << "a buffer of 0 bytes was created";
  } catch (const cl::Error& e) {
    const std::string message = DescribeException(e);
    EXPECT_NE(message.find("OpenCL call clCreateBuffer failed: CL_INVALID_BUFFER_SIZE (-61)"),
              std::string::npos)
        << message;
    EXPECT_NE(message.find("--OrientationStereo.max_image_size"), std::string::npos) << message;
    EXPECT_NE(message.find("--OrientationStereo.slice_block"), std::string::npos) << message;
  }
  // Every code an OpenCL 1.2 call can return is named (-20 to -29 are no codes).
  for (int code = -68; code <= 0; ++code) {
    if (code <= -20 && code >= -29) continue;
    EXPECT_EQ(OpenCLErrorString(code).find("unknown"), std::string::npos) << code;
  }
  EXPECT_EQ(OpenCLErrorString(CL_MAP_FAILURE), "CL_MAP_FAILURE (-12)");
  EXPECT_EQ(DescribeException(Error("plain")), "plain");
  // Host memory that ran out: said so, with what to do on the host.
  const std::string host = DescribeException(std::bad_alloc());
  EXPECT_EQ(host.rfind("out of host memory", 0), 0u) << host;
  EXPECT_NE(host.find("--OrientationStereo.max_image_size"), std::string::npos) << host;
  EXPECT_NE(host.find("--image_names"), std::string::npos) << host;
  EXPECT_EQ(host.find("slice_block"), std::string::npos) << host;
  // Within a view: prefixed with where it struck, unless the message names the view first.
  const std::string where = "v0.png: MRF";
  EXPECT_EQ(DescribeExceptionWithin("v0.png", where, std::bad_alloc()), where + ": " + host);
  EXPECT_EQ(DescribeExceptionWithin("v0.png", where, cl::Error(CL_OUT_OF_RESOURCES, "clFinish"))
                .rfind("v0.png: MRF: OpenCL call clFinish failed: CL_OUT_OF_RESOURCES", 0),
            0u);
  EXPECT_EQ(DescribeExceptionWithin("v0.png", where, Error("v0.png: no depth range")),
            "v0.png: no depth range");
  EXPECT_EQ(DescribeExceptionWithin("v0.png", where, Error("v0.png.bin is missing")),
            "v0.png: MRF: v0.png.bin is missing");
}

// A buffer beyond the device's largest allocation is refused before it is asked for, naming its
// size, the device, the limit and what to do; one within the limit is made with its flags.
TEST(OpenCLContext, BufferBeyondTheLargestAllocationIsNamed) {
  auto context = OpenCLContext::Create();
  const size_t max_alloc = context->MaxAllocBytes();
  EXPECT_EQ(max_alloc, context->Device().getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>());
  const std::string message =
      testing_util::ErrorOf([&] { context->Buffer(CL_MEM_READ_WRITE, max_alloc + 1); });
  EXPECT_NE(message.find("(" + std::to_string(max_alloc + 1) + " bytes) exceeds the largest "
                         "allocation of OpenCL device '" + context->DeviceName() + "'"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("--OrientationStereo.max_image_size"), std::string::npos) << message;
  std::vector<float> host = {1.5f, -2.0f, 3.25f};
  const cl::Buffer copied = context->Buffer(CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                                            sizeof(float) * host.size(), host.data());
  EXPECT_EQ(copied.getInfo<CL_MEM_FLAGS>(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR);
  std::vector<float> read(host.size());
  context->Queue().enqueueReadBuffer(copied, CL_TRUE, 0, sizeof(float) * read.size(), read.data());
  EXPECT_EQ(read, host);
}

// Data shorter than the 4 bytes a buffer needs (an empty array, whose data() may be null; one
// byte) is padded with zeros, not read beyond; longer data is copied as it is.
TEST(OpenCLContext, ReadOnlyBufferOfShortData) {
  auto context = OpenCLContext::Create();
  auto read_back = [&](const cl::Buffer& buffer) {
    std::vector<unsigned char> bytes(buffer.getInfo<CL_MEM_SIZE>());
    context->Queue().enqueueReadBuffer(buffer, CL_TRUE, 0, bytes.size(), bytes.data());
    return bytes;
  };
  const std::vector<float> empty;
  EXPECT_EQ(read_back(ReadOnlyBuffer(context.get(), empty)),
            (std::vector<unsigned char>{0, 0, 0, 0}));
  const unsigned char one_byte = 7;
  EXPECT_EQ(read_back(ReadOnlyBuffer(context.get(), &one_byte, 1)),
            (std::vector<unsigned char>{7, 0, 0, 0}));
  const std::vector<unsigned char> six = {1, 2, 3, 4, 5, 6};
  EXPECT_EQ(read_back(ReadOnlyBuffer(context.get(), six)), six);
}

TEST(OpenCLContext, DeviceSelection) {
  const auto devices = ListOpenCLDevices();
  ASSERT_FALSE(devices.empty());
  EXPECT_FALSE(OpenCLDevicesTable(devices).empty());
  EXPECT_EQ(OpenCLContext::Create("0")->DeviceName(), devices[0].device_name);
  EXPECT_EQ(OpenCLContext::Create(devices[0].device_name.substr(0, 6))->DeviceName(),
            devices[0].device_name);
  // An index past the devices, also one of more digits than a long holds.
  for (const std::string index : {"999", "99999999999999999999"}) {
    try {
      OpenCLContext::Create(index);
      FAIL() << "expected an error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("--OpenCL.device " + index + ": no such device index"),
                std::string::npos)
          << e.what();
    }
  }
  OpenCLOptions options;
  options.device = "no-such-device-xyz";
  try {
    options.CreateContext();
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-device-xyz"), std::string::npos) << e.what();
  }
}

// The ICD loader reads OCL_ICD_VENDORS: pointing it at an empty folder simulates a machine
// without any OpenCL driver. Run in a child process so the loader state of this one stays.
TEST(OpenCLContext, MissingPlatformGivesClearError) {
  const std::string command =
      std::string("OCL_ICD_VENDORS=/nonexistent_hairmvs_vendors ") + HAIRMVS_BINARY_DIR +
      "/src/opencl/opencl_test --gtest_filter=OpenCLContext.DISABLED_ChildNoPlatform "
      "--gtest_also_run_disabled_tests 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  char buffer[256];
  while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr) output += buffer;
  EXPECT_EQ(pclose(pipe), 0) << output;
  // The child must really have run the one test (and passed it).
  EXPECT_NE(output.find("[  PASSED  ] 1 test."), std::string::npos) << output;
}

TEST(OpenCLContext, DISABLED_ChildNoPlatform) {
  try {
    OpenCLContext::Create();
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("No OpenCL platform"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("pocl-opencl-icd"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hairmvs
