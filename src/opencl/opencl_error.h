#pragma once
// What the user reads when a command fails, without OpenCL's headers: the CLI's last line.

#include <exception>
#include <string>

namespace hairmvs {

// e.what(); for a failed OpenCL call (cl::Error, whose what() is only the call's name) the
// call, the error code by name and, where the code means that memory ran out, what to do; for
// std::bad_alloc (host memory) what to do too.
std::string DescribeException(const std::exception& e);

}  // namespace hairmvs
