#pragma once
// Option enums by name: one table of (value, name) pairs per enum gives both its ToString and
// its FromString (which OptionParser calls), so that the two cannot disagree and a new value
// is one line.
//
//   constexpr std::pair<Color, const char*> kColorNames[] = {{Color::kRed, "red"}, ...};
//   std::string ToString(Color c) { return EnumName(kColorNames, c); }
//   bool FromString(const std::string& s, Color* c) { return EnumFromName(kColorNames, s, c); }

#include <cstddef>
#include <string>
#include <utility>

namespace hairmvs {

template <typename Enum, std::size_t N>
std::string EnumName(const std::pair<Enum, const char*> (&table)[N], Enum value) {
  for (const auto& [entry, name] : table) {
    if (entry == value) return name;
  }
  return "?";
}

template <typename Enum, std::size_t N>
bool EnumFromName(const std::pair<Enum, const char*> (&table)[N], const std::string& text,
                  Enum* value) {
  for (const auto& [entry, name] : table) {
    if (text == name) {
      *value = entry;
      return true;
    }
  }
  return false;
}

}  // namespace hairmvs
