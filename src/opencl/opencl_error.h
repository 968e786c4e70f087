#pragma once
// What the user reads when a command fails, without OpenCL's headers: the CLI's last line.

#include <exception>
#include <string>

namespace hairmvs {

// e.what(); for a failed OpenCL call (cl::Error, whose what() is only the call's name) the
// call, the error code by name and, where the code means that memory ran out, what to do; for
// std::bad_alloc (host memory) what to do too.
std::string DescribeException(const std::exception& e);

// The message of an error raised while working on `item` at `where` ("g0_c.png: MRF"):
// DescribeException's, prefixed with `where` unless it begins with the item's name already
// ("g0_c.png: no depth range ..."): a failed OpenCL call or memory that ran out names neither.
std::string DescribeExceptionWithin(const std::string& item, const std::string& where,
                                    const std::exception& e);

}  // namespace hairmvs
