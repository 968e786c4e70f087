#pragma once
// The one place that configures the OpenCL C++ bindings. Every file of hairmvs that needs
// OpenCL includes this header, never <CL/opencl.hpp> directly, so that all translation units
// agree on the target version (OpenCL 1.2: what PoCL 3.1 and most GPUs support fully) and on
// exceptions (cl::Error carries the failing call and the error code).

#ifndef CL_HPP_TARGET_OPENCL_VERSION
#define CL_HPP_TARGET_OPENCL_VERSION 120
#endif
#ifndef CL_HPP_MINIMUM_OPENCL_VERSION
#define CL_HPP_MINIMUM_OPENCL_VERSION 120
#endif
#ifndef CL_HPP_ENABLE_EXCEPTIONS
#define CL_HPP_ENABLE_EXCEPTIONS
#endif

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wignored-attributes"
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#endif
#include <CL/opencl.hpp>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include <string>

namespace hairmvs {

// "CL_OUT_OF_RESOURCES (-5)" for an OpenCL error code.
std::string OpenCLErrorString(cl_int code);

}  // namespace hairmvs
