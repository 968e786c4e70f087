#pragma once
// The `--OpenCL.*` options every OpenCL-using command shares:
//   OpenCLOptions opencl_options;
//   parser.AddSection("OpenCL", &opencl_options);
//   auto context = opencl_options.CreateContext();

#include <memory>
#include <string>

namespace hairmvs {

class OpenCLContext;

struct OpenCLOptions {
  // "" = the first GPU, else the first CPU device; an index of `hairmvs opencl_devices`; or a
  // substring of "platform / device" name (case-insensitive), e.g. "pocl".
  std::string device;

  template <typename Visitor>
  void ForEachField(Visitor&& v) {
    v("device", &device,
      "OpenCL device: empty = first GPU else first CPU; an index from `hairmvs opencl_devices`; "
      "or a substring of the platform/device name");
  }
  bool Check(std::string* error) const;
  // Throws hairmvs::Error naming --OpenCL.device when no such device exists.
  std::shared_ptr<OpenCLContext> CreateContext() const;
};

}  // namespace hairmvs
