#pragma once
// Command-line options in COLMAP's style: `hairmvs <command> --workspace_path W
// --Section.option value`, `-h` per command. Each *Options struct keeps the one list of its
// fields in a ForEachField(visitor) member; the CLI, the help text and the printout of the
// values in use all derive from it:
//
//   struct FooOptions {
//     double lambda = 0.5;  // why this default
//     template <typename Visitor> void ForEachField(Visitor&& v) {
//       v("lambda", &lambda, "smoothness weight (paper Eq. 3)");
//     }
//     bool Check(std::string* error) const;
//   };
//   OptionParser parser("orientation_stereo", "...");
//   parser.AddSection("OrientationStereo", &foo_options);
//
// Supported field types: bool (0/1/true/false), int, int64, double, float, std::string,
// std::vector<std::string> (comma-separated), and enum classes that provide
// `std::string ToString(E)` and `bool FromString(const std::string&, E*)` found by ADL.

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

namespace hairmvs {

class OptionParser {
 public:
  OptionParser(std::string command, std::string description);
  ~OptionParser();

  void Add(const std::string& name, bool* value, const std::string& help, bool required = false);
  void Add(const std::string& name, int* value, const std::string& help, bool required = false);
  void Add(const std::string& name, long* value, const std::string& help, bool required = false);
  void Add(const std::string& name, double* value, const std::string& help, bool required = false);
  void Add(const std::string& name, float* value, const std::string& help, bool required = false);
  void Add(const std::string& name, std::string* value, const std::string& help,
           bool required = false);
  void Add(const std::string& name, std::vector<std::string>* value, const std::string& help,
           bool required = false);

  template <typename E, typename = std::enable_if_t<std::is_enum_v<E>>>
  void Add(const std::string& name, E* value, const std::string& help, bool required = false) {
    AddConverted(
        name, ToString(*value), help, required,
        [value](const std::string& text) { return FromString(text, value); },
        [value] { return ToString(*value); });
  }

  // Adds every field of an options struct as `--Section.field`, except those of
  // `ignored_fields` (field -> why), which another of the command's options decides: those are
  // added as AddIgnored, so that giving one warns rather than silently doing nothing.
  template <typename OptionsT>
  void AddSection(const std::string& section, OptionsT* options,
                  const std::map<std::string, std::string>& ignored_fields = {}) {
    options->ForEachField(
        [this, &section, &ignored_fields](const char* field, auto* ptr, const char* help) {
          const auto ignored = ignored_fields.find(field);
          if (ignored != ignored_fields.end()) {
            AddIgnored(section + "." + field, ignored->second);
          } else {
            Add(section + "." + field, ptr, help);
          }
        });
  }

  // An option accepted for compatibility (e.g. one of colmap patch_match_stereo's) but
  // without effect here: if given, a warning says it is ignored and why.
  void AddIgnored(const std::string& name, const std::string& why);

  // `--project_path FILE`, as every colmap command takes it: an .ini file of options
  // (`key=value` at the top, `[Section]` then `key=value` for `--Section.key`), as colmap
  // project_generator and colmap's GUI write it. Options given on the command line win over
  // the file's; the file's sections for other commands are passed over, its options of
  // `sections` (colmap's) that are ignored here are named in one warning and those unknown in
  // another, and an unknown key in a section of the command's own options (a typo) is an
  // error. A missing or malformed file is an error naming it.
  void AddProjectPath(const std::vector<std::string>& sections);
  // Parses argv[first..argc). Returns false when help was requested (and printed).
  // Throws hairmvs::Error on an unknown option, a missing value or a bad value.
  bool Parse(int argc, char** argv, int first = 2);
  bool WasGiven(const std::string& name) const;
  // Whether `name`'s value came from the --project_path file (not the command line).
  bool FromProjectFile(const std::string& name) const;
  std::string Help() const;
  // "name = value" lines for the values in use, for logs.
  std::string Values() const;

 private:
  void AddConverted(const std::string& name, const std::string& default_text,
                    const std::string& help, bool required,
                    std::function<bool(const std::string&)> parse,
                    std::function<std::string()> print);

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hairmvs
