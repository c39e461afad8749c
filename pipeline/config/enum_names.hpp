#pragma once
// The spelling of an enum's values in configuration files and outputs, declared once per enum as
// a table of (name, value) pairs; toString / parse / the list of choices derive from it.
#include <array>
#include <cstddef>
#include <string>
#include <utility>

namespace svslam::config {

template <typename E, std::size_t N>
using EnumNames = std::array<std::pair<const char*, E>, N>;

// The name of `v` in `names` ("?" when absent).
template <typename E, std::size_t N>
const char* nameOf(const EnumNames<E, N>& names, E v) {
  for (const auto& [name, value] : names)
    if (value == v) return name;
  return "?";
}

// The value named `s`; false (out untouched) when `s` names none.
template <typename E, std::size_t N>
bool parseName(const EnumNames<E, N>& names, const std::string& s, E& out) {
  for (const auto& [name, value] : names)
    if (s == name) {
      out = value;
      return true;
    }
  return false;
}

// "a | b | c".
template <typename E, std::size_t N>
std::string nameList(const EnumNames<E, N>& names) {
  std::string list;
  for (const auto& [name, value] : names) list += (list.empty() ? "" : " | ") + std::string(name);
  return list;
}

}  // namespace svslam::config
