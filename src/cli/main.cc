// hairmvs: multi-view hair reconstruction from orientation fields, for COLMAP workspaces.
// Usage: hairmvs <command> [options]; hairmvs help; hairmvs <command> -h.

#include <cstdio>
#include <exception>
#include <string>

#include "src/cli/command_registry.h"
#include "src/core/file_util.h"
#include "src/core/logging.h"
#include "src/opencl/opencl_error.h"

namespace hairmvs {

std::map<std::string, CommandInfo>& CommandTable() {
  static std::map<std::string, CommandInfo> table;
  return table;
}

namespace {

int PrintHelp() {
  std::printf(
      "hairmvs: multi-view hair capture from orientation fields (Luo et al., CVPR 2012),\n"
      "for COLMAP dense workspaces.\n\n"
      "Usage:\n  hairmvs <command> [options]\n  hairmvs <command> -h\n\nCommands:\n");
  for (const auto& [name, info] : CommandTable()) {
    std::printf("  %-22s %s\n", name.c_str(), info.summary.c_str());
  }
  return 0;
}

}  // namespace
}  // namespace hairmvs

int main(int argc, char** argv) {
  // Line by line, as stderr's progress is: a log redirected to a file (a cluster job's) keeps
  // the two in the order they were written.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  hairmvs::InitLogging(argv[0]);
  hairmvs::RemoveTemporaryFilesOnInterrupt();
  if (argc < 2) {
    hairmvs::PrintHelp();
    return 1;
  }
  const std::string command = argv[1];
  if (command == "help" || command == "-h" || command == "--help") return hairmvs::PrintHelp();
  const auto& table = hairmvs::CommandTable();
  const auto it = table.find(command);
  if (it == table.end()) {
    std::fprintf(stderr, "hairmvs: unknown command '%s' (see hairmvs help)\n",
                 hairmvs::PrintableText(command).c_str());
    return 1;
  }
  try {
    return it->second.run(argc, argv);
  } catch (const std::exception& e) {  // hairmvs::Error, OpenCL's and the others alike
    // What the command printed (its options, its progress) comes first, so that the error is
    // the last line of a log that captures both streams.
    std::fflush(stdout);
    // Messages quote files' bytes (a bad config line, a PLY header).
    std::fprintf(stderr, "ERROR: %s\n",
                 hairmvs::PrintableText(hairmvs::DescribeException(e)).c_str());
    return 1;
  }
}
