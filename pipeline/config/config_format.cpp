// The documented configuration file: the declaration tables walked in order, each key with its
// value and a comment "[range unit] doc".
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <sstream>

#include "pipeline/config/config_keys.hpp"

namespace svslam::config {
namespace {

constexpr std::size_t kCommentColumn = 27;  // where comments start, characters
constexpr std::size_t kMaxColumns = 100;    // comments wrap beyond, characters

template <typename T>
std::string shortest(T v) {
  char buf[64];
  const std::string s(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
  if (s.find_first_of(".ein") != std::string::npos) {
    if (s.find('.') == std::string::npos && s.find('e') != std::string::npos)
      return s.substr(0, s.find('e')) + ".0" + s.substr(s.find('e'));  // 1e+09 -> 1.0e+09
    return s;
  }
  return s + ".0";  // 10 -> 10.0: reads as a floating value
}

std::string quoted(const std::string& v) {
  std::string q = "\"";
  for (char ch : v) {
    if (ch == '"' || ch == '\\') q += '\\';
    if (ch == '\n') {
      q += "\\n";
      continue;
    }
    if (ch == '\t') {
      q += "\\t";
      continue;
    }
    q += ch;
  }
  return q + "\"";
}

// "key: value" padded to the comment column, then the comment, wrapped at kMaxColumns onto
// comment lines starting at the comment column.
std::string line(int depth, const std::string& name, const std::string& value,
                 const std::string& comment) {
  std::string s = std::string(2 * depth, ' ') + name + ":" + (value.empty() ? "" : " " + value);
  if (comment.empty()) return s + "\n";
  s += s.size() < kCommentColumn ? std::string(kCommentColumn - s.size(), ' ') : "  ";
  s += "#";
  std::size_t width = s.size();  // of the current output line
  std::istringstream words(comment);
  std::string w;
  bool first = true;
  while (words >> w) {
    if (!first && width + 1 + w.size() > kMaxColumns) {
      s += "\n" + std::string(kCommentColumn, ' ') + "#";
      width = kCommentColumn + 1;
    }
    s += " " + w;
    width += 1 + w.size();
    first = false;
  }
  return s + "\n";
}

// "[range unit] doc".
std::string comment(const ConfigKey& k) {
  std::string head = k.range;
  if (!k.unit.empty()) head += (head.empty() ? "" : " ") + k.unit;
  return head.empty() ? k.doc : "[" + head + "] " + k.doc;
}

std::vector<std::string> split(const std::string& dotted) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (!dotted.empty()) {
    const std::size_t dot = dotted.find('.', start);
    parts.push_back(dotted.substr(start, dot == std::string::npos ? dot : dot - start));
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return parts;
}

constexpr const char* kHeader =
    "# svslam run: configuration with every key at its default value.\n"
    "# Printed by `svslam config --defaults` from the key declarations\n"
    "# (pipeline/config/*_keys.cpp); a test fails when this file differs from that output.\n"
    "# Every key is optional. Unknown keys, renamed keys and out-of-range values are rejected "
    "with\n"
    "# a message naming the key. Each comment: [range or choices, unit] meaning.\n"
    "# Units: px = pixels, m = metres, s = seconds, rad = radians, deg = degrees, Hz = per "
    "second.\n";

}  // namespace

std::string formatValue(double v) { return shortest(v); }
std::string formatValue(float v) { return shortest(v); }
std::string formatValue(int v) { return std::to_string(v); }
std::string formatValue(std::uint64_t v) { return std::to_string(v); }
std::string formatValue(bool v) { return v ? "true" : "false"; }

std::string formatValue(const std::vector<int>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s + "]";
}

std::string formatValue(const std::string& v) {
  const std::string safe_first =
      "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_/.";
  const std::string safe = safe_first + ":?=@+-,%~";
  const bool plain = !v.empty() && safe_first.find(v[0]) != std::string::npos &&
                     v.find_first_not_of(safe) == std::string::npos;
  if (plain) {
    try {  // a plain scalar must read back as the same text
      const YAML::Node n = YAML::Load("k: " + v)["k"];
      if (n.IsScalar() && n.Scalar() == v) return v;
    } catch (const YAML::Exception&) {
    }
  }
  return quoted(v);
}

std::string formatRunConfig(const RunConfig& cfg) {
  std::ostringstream out;
  std::vector<std::string> open;  // the maps the previous section was in
  for (const ConfigSection& s : allConfigSections()) {
    const std::vector<std::string> path = split(s.name);
    std::size_t common = 0;
    while (common < path.size() && common < open.size() && path[common] == open[common]) ++common;
    if (common == 0) out << "\n";  // a new top-level section (or the top-level keys)
    for (std::size_t d = common; d < path.size(); ++d)
      out << line(static_cast<int>(d), path[d], "", d + 1 == path.size() ? s.doc : "");
    for (const ConfigKey& k : s.keys)
      out << line(static_cast<int>(path.size()), k.name, k.value(cfg), comment(k));
    open = path;
  }
  return out.str();
}

std::string defaultsYaml() { return kHeader + formatRunConfig(RunConfig{}); }

}  // namespace svslam::config
