#include "src/core/option_parser.h"

#include <algorithm>
#include <boost/program_options.hpp>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <type_traits>

#include "src/core/file_util.h"
#include "src/core/logging.h"

namespace po = boost::program_options;

namespace hairmvs {

struct OptionParser::Impl {
  std::string command;
  std::string description;
  po::options_description desc{"Options"};
  po::variables_map vm;
  std::vector<std::string> names;
  std::map<std::string, std::function<std::string()>> printers;
  std::map<std::string, std::function<bool(const std::string&)>> converters;
  std::map<std::string, std::string> ignored;
  // The option each typed variable is bound to: boost's notify() stores every option's value,
  // defaults too, so a second option on one variable would overwrite a value given to the
  // first with its own default.
  std::map<const void*, std::string> typed_targets;
  // Per floating-point option: whether its value is finite. The stream parser takes "inf" and
  // "nan", which no option means and which pass many a range check (nan fails every
  // comparison, inf passes every lower bound).
  std::map<std::string, std::function<bool()>> finite_checks;
  // AddProjectPath's sections; empty without it.
  std::vector<std::string> project_sections;
  // The options whose value the project file gave.
  std::set<std::string> from_project_file;
};

OptionParser::OptionParser(std::string command, std::string description)
    : impl_(std::make_unique<Impl>()) {
  impl_->command = std::move(command);
  impl_->description = std::move(description);
  impl_->desc.add_options()("help,h", "print this help");
}

OptionParser::~OptionParser() = default;

namespace {

// A number as typed back: the fewest significant digits (6 at least, as a stream prints) that
// read back as the same value, so that 0.12 prints as 0.12 and 0.3333333 not as 0.333333 (the
// printed values are also what the orientation fields' cache compares).
template <typename T>
std::string ToText(const T& value) {
  std::ostringstream ss;
  if constexpr (std::is_floating_point_v<T>) {
    for (int digits = 6; digits <= std::numeric_limits<T>::max_digits10; ++digits) {
      ss.str("");
      ss << std::setprecision(digits) << value;
      std::istringstream back(ss.str());
      T read = 0;
      if ((back >> read) && read == value) break;
    }
  } else {
    ss << value;
  }
  return ss.str();
}

// Whether a floating-point option's value is finite; null for other types.
template <typename T>
std::function<bool()> FiniteCheck(const T* value) {
  if constexpr (std::is_floating_point_v<T>) {
    return [value] { return std::isfinite(*value); };
  } else {
    return nullptr;
  }
}

std::string JoinNames(const std::vector<std::string>& values) {
  std::string out;
  for (size_t i = 0; i < values.size(); ++i) out += (i ? "," : "") + values[i];
  return out;
}

}  // namespace

#define HAIRMVS_ADD_TYPED_OPTION(TYPE)                                                      \
  void OptionParser::Add(const std::string& name, TYPE* value, const std::string& help,   \
                         bool required) {                                                  \
    const auto [bound, inserted] = impl_->typed_targets.emplace(value, name);             \
    THROW_IF(!inserted, "hairmvs " << impl_->command << ": --" << name << " and --"        \
                                   << bound->second << " are bound to one variable");     \
    auto* semantic = po::value<TYPE>(value);                                               \
    if (required) semantic->required();                                                    \
    else semantic->default_value(*value, ToText(*value));                                  \
    impl_->desc.add_options()(name.c_str(), semantic, help.c_str());                       \
    impl_->names.push_back(name);                                                          \
    impl_->printers[name] = [value] { return ToText(*value); };                            \
    if (auto check = FiniteCheck(value)) impl_->finite_checks[name] = std::move(check);   \
  }

HAIRMVS_ADD_TYPED_OPTION(int)
HAIRMVS_ADD_TYPED_OPTION(long)
HAIRMVS_ADD_TYPED_OPTION(double)
HAIRMVS_ADD_TYPED_OPTION(float)
HAIRMVS_ADD_TYPED_OPTION(std::string)
#undef HAIRMVS_ADD_TYPED_OPTION

void OptionParser::Add(const std::string& name, bool* value, const std::string& help,
                       bool required) {
  AddConverted(
      name, *value ? "1" : "0", help, required,
      [value](const std::string& given) {
        // Any case, as colmap's parser takes them ("True", "YES").
        const std::string text = ToLower(given);
        if (text == "1" || text == "true" || text == "on" || text == "yes") *value = true;
        else if (text == "0" || text == "false" || text == "off" || text == "no") *value = false;
        else return false;
        return true;
      },
      [value] { return std::string(*value ? "1" : "0"); });
}

void OptionParser::Add(const std::string& name, std::vector<std::string>* value,
                       const std::string& help, bool required) {
  AddConverted(
      name, JoinNames(*value), help, required,
      [value](const std::string& text) {
        value->clear();
        for (const std::string& part : SplitString(text, ",;")) {
          const std::string item = StripWhitespace(part);
          if (!item.empty()) value->push_back(item);
        }
        // Separators alone name nothing; taken as "all" (the empty list), they ran every image.
        return !value->empty() || StripWhitespace(text).empty();
      },
      [value] { return JoinNames(*value); });
}

void OptionParser::AddConverted(const std::string& name, const std::string& default_text,
                                const std::string& help, bool required,
                                std::function<bool(const std::string&)> parse,
                                std::function<std::string()> print) {
  auto* semantic = po::value<std::string>();
  if (required) semantic->required();
  else semantic->default_value(default_text);
  impl_->desc.add_options()(name.c_str(), semantic, help.c_str());
  impl_->names.push_back(name);
  impl_->printers[name] = std::move(print);
  impl_->converters[name] = std::move(parse);
}

void OptionParser::AddIgnored(const std::string& name, const std::string& why) {
  impl_->desc.add_options()(name.c_str(), po::value<std::string>(),
                            ("accepted for compatibility, ignored: " + why).c_str());
  impl_->ignored[name] = why;
}

void OptionParser::AddProjectPath(const std::vector<std::string>& sections) {
  CHECK(!sections.empty()) << "AddProjectPath needs the sections the file's options may set";
  impl_->desc.add_options()("project_path", po::value<std::string>(),
                            "colmap project .ini file of options (those given here win)");
  impl_->project_sections = sections;
}

namespace {

// Whether `key` ("Section.name") belongs to one of `sections`.
bool InSections(const std::string& key, const std::vector<std::string>& sections) {
  for (const std::string& section : sections) {
    if (key.rfind(section + ".", 0) == 0) return true;
  }
  return false;
}

}  // namespace

bool OptionParser::Parse(int argc, char** argv, int first) {
  std::vector<std::string> args(argv + first, argv + argc);
  // The project file's options without effect here (named in one warning of their own).
  std::vector<std::string> not_used;
  try {
    // A word that is not an option (a value given twice, a forgotten "--") is an error naming
    // it rather than dropped: every positional word lands in a hidden option, refused below.
    // (The parser keeps pointers to both descriptions.)
    constexpr const char* kStray = "hairmvs-stray-word";
    po::options_description with_stray;
    with_stray.add(impl_->desc).add_options()(kStray, po::value<std::vector<std::string>>());
    po::positional_options_description stray_words;
    stray_words.add(kStray, -1);
    po::store(po::command_line_parser(args).options(with_stray).positional(stray_words).run(),
              impl_->vm);
    if (impl_->vm.count(kStray)) {
      const std::vector<std::string> words = impl_->vm[kStray].as<std::vector<std::string>>();
      HAIRMVS_THROW("hairmvs " << impl_->command << ": unexpected word '" << words.front()
                                << "' (options are --name value or --name=value; see hairmvs "
                                << impl_->command << " -h)");
    }
    if (impl_->vm.count("help")) {
      std::cout << Help();
      return false;
    }
    if (!impl_->project_sections.empty() && impl_->vm.count("project_path")) {
      // Stored after the command line: boost keeps the first value stored of an option.
      const std::string path = impl_->vm["project_path"].as<std::string>();
      RequireFile(path, "project file (--project_path)");
      std::istringstream in(ReadTextFile(path));
      po::parsed_options from_file(nullptr);
      try {
        from_file = po::parse_config_file(in, impl_->desc, /*allow_unregistered=*/true);
      } catch (const po::error& e) {
        HAIRMVS_THROW("--project_path " << path << ": " << e.what());
      }
      // The sections of this command's own options (--Section.field): a key the file gives
      // there that is none of them is a typo, refused as the command line refuses it.
      std::set<std::string> own_sections;
      for (const std::string& name : impl_->names) {
        const size_t dot = name.find('.');
        if (dot != std::string::npos) own_sections.insert(name.substr(0, dot));
      }
      // The file's options that take effect, and those of colmap's sections without effect
      // (named once here, rather than warned about one by one: a generated file lists them
      // all). A colmap section's key unknown here may be a typo or an option of another colmap
      // version: named apart.
      std::vector<std::string> used, unknown_own, unknown_colmap;
      for (const po::option& option : from_file.options) {
        const std::string& key = option.string_key;
        // Given on the command line (the file's values are not stored yet): that value wins.
        if (WasGiven(key)) continue;
        if (!option.unregistered && impl_->ignored.count(key) == 0) {
          used.push_back(key + "=" + (option.value.empty() ? "" : option.value.front()));
          impl_->from_project_file.insert(key);
        } else if (impl_->ignored.count(key) > 0) {
          not_used.push_back(key);  // ignored here (colmap's top-level log_level too)
        } else if (InSections(key, impl_->project_sections)) {
          unknown_colmap.push_back(key);
        } else if (key.find('.') != std::string::npos &&
                   own_sections.count(key.substr(0, key.find('.'))) > 0) {
          unknown_own.push_back(key);
        }
        // Other commands' sections are passed over.
      }
      THROW_IF(!unknown_own.empty(), "--project_path "
                                         << path << ": unknown option"
                                         << (unknown_own.size() > 1 ? "s " : " ")
                                         << JoinStrings(unknown_own, ", ") << " (see hairmvs "
                                         << impl_->command << " -h)");
      po::store(from_file, impl_->vm);
      LOG(INFO) << path << ": options read from it: "
                << (used.empty() ? "none" : JoinStrings(used, ", "));
      if (!not_used.empty()) {
        LOG(WARNING) << path << ": " << not_used.size() << " of its options have no effect "
                     << "in hairmvs (see hairmvs " << impl_->command
                     << " -h for why): " << JoinStrings(not_used, ", ");
      }
      if (!unknown_colmap.empty()) {
        LOG(WARNING) << path << ": " << unknown_colmap.size() << " of its options are unknown "
                     << "to hairmvs and colmap 3.8 (a typo, or another colmap version's?), "
                     << "not applied: " << JoinStrings(unknown_colmap, ", ");
      }
    }
    po::notify(impl_->vm);
  } catch (const po::error& e) {
    HAIRMVS_THROW("hairmvs " << impl_->command << ": " << e.what()
                              << " (see hairmvs " << impl_->command << " -h)");
  }
  for (auto& [name, parse] : impl_->converters) {
    if (!impl_->vm.count(name) || impl_->vm[name].defaulted()) continue;
    const std::string text = impl_->vm[name].as<std::string>();
    // The option's help repeated: for an enum it lists the accepted names.
    THROW_IF(!parse(text), "hairmvs " << impl_->command << ": invalid value '" << text
                                      << "' for --" << name << " ("
                                      << impl_->desc.find(name, false).description() << ")");
  }
  for (const auto& [name, is_finite] : impl_->finite_checks) {
    THROW_IF(!is_finite(), "hairmvs " << impl_->command << ": invalid value '"
                                      << impl_->printers[name]() << "' for --" << name
                                      << ": not a finite number");
  }
  for (const auto& [name, why] : impl_->ignored) {
    // Those the project file set are named in its one warning above.
    const bool named_above = std::find(not_used.begin(), not_used.end(), name) != not_used.end();
    if (impl_->vm.count(name) && !named_above) {
      LOG(WARNING) << "--" << name << " is ignored by hairmvs: " << why;
    }
  }
  return true;
}

bool OptionParser::WasGiven(const std::string& name) const {
  return impl_->vm.count(name) && !impl_->vm[name].defaulted();
}

bool OptionParser::FromProjectFile(const std::string& name) const {
  return impl_->from_project_file.count(name) > 0;
}

std::string OptionParser::Help() const {
  std::ostringstream out;
  out << "hairmvs " << impl_->command << ": " << impl_->description << "\n\n" << impl_->desc;
  return out.str();
}

std::string OptionParser::Values() const {
  std::ostringstream out;
  for (const std::string& name : impl_->names) {
    out << "  " << name << " = " << impl_->printers.at(name)() << "\n";
  }
  return out.str();
}

}  // namespace hairmvs
