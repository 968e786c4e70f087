#pragma once
// The hairmvs command table. Each file of src/cli/ registers its commands with
// HAIRMVS_REGISTER_COMMAND; the files are compiled into the executable itself (not a static
// library), so the registrations are never dropped by the linker.

#include <functional>
#include <map>
#include <string>

namespace hairmvs {

using CommandFunction = std::function<int(int argc, char** argv)>;

struct CommandInfo {
  CommandFunction run;
  std::string summary;
};

std::map<std::string, CommandInfo>& CommandTable();

struct CommandRegistrar {
  CommandRegistrar(const std::string& name, CommandFunction run, const std::string& summary) {
    CommandTable()[name] = {std::move(run), summary};
  }
};

}  // namespace hairmvs

#define HAIRMVS_REGISTER_COMMAND(name, function, summary) \
  static ::hairmvs::CommandRegistrar hairmvs_registrar_##function(name, function, summary)
