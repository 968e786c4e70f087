#include "src/opencl/opencl_options.h"

#include "src/core/logging.h"
#include "src/opencl/opencl_context.h"

namespace hairmvs {

bool OpenCLOptions::Check(std::string* error) const {
  for (const char c : device) {
    if (c == '\n' || c == '\r') {
      if (error != nullptr) *error = "--OpenCL.device must be a single line";
      return false;
    }
  }
  return true;
}

std::shared_ptr<OpenCLContext> OpenCLOptions::CreateContext() const {
  std::string error;
  THROW_IF(!Check(&error), error);
  return OpenCLContext::Create(device);
}

}  // namespace hairmvs
