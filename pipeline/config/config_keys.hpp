#pragma once
// The declaration table of the `svslam run` configuration: each key once, with the RunConfig
// field it sets, its unit, its range or choices and a one-line doc. Its default is the field's
// value in a default-constructed RunConfig (declared in the struct). The reader (run_config.cpp)
// and the documented defaults file (config_format.cpp, `svslam config --defaults`) both walk
// these tables.
//
// A section is a YAML map ("detector", "pipeline.scheduling.capture"; "" = the top level); its
// keys are named relative to it. Builders:
//   number(key, field, lo, hi, unit, doc)  int / float / double in [lo, hi]
//   flag(key, field, doc)                  bool
//   text(key, field, doc)                  any string
//   unsignedInt(key, field, doc)           std::uint64_t (seeds)
//   choice(key, field, names, doc)         an enum spelt by an EnumNames table
// `field` is a generic lambda returning a reference into the RunConfig, SVSLAM_FIELD(path).
#include <charconv>
#include <cstdint>
#include <functional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/status.hpp"
#include "pipeline/config/enum_names.hpp"
#include "pipeline/config/run_config.hpp"
#include "pipeline/config/yaml_config.hpp"

// A reference to the member `path` of a (const or not) RunConfig.
#define SVSLAM_FIELD(path) \
  [](auto& c) -> auto& { return c.path; }

namespace svslam::config {

struct ConfigKey {
  std::string name;   // relative to the section
  std::string unit;   // "px", "m", "s", ...; empty for counts, ratios, flags and text
  std::string range;  // "0.5..5", "harris | shi-tomasi"; empty when any value of the type goes
  std::string doc;    // one line
  // Reads the key `full_name` of the file into the config (absent: untouched; checks the range).
  std::function<Status(ConfigReader&, const std::string& full_name, RunConfig&)> read;
  // The YAML text of the key's value in a config (reads back to the same value).
  std::function<std::string(const RunConfig&)> value;
};

struct ConfigSection {
  std::string name;  // dotted path of the map; "" = top level
  std::string doc;   // one line, on the map's own line
  std::vector<ConfigKey> keys;
};

// Every section in file order: run_config_keys.cpp (with slam_config_keys.cpp and
// map_config_keys.cpp), then
// pipeline_config_keys.cpp.
std::vector<ConfigSection> runConfigSections();
ConfigSection slamConfigSection();
ConfigSection mapConfigSection();
ConfigSection loopConfigSection();
std::vector<ConfigSection> pipelineConfigSections();
const std::vector<ConfigSection>& allConfigSections();

// Keys of earlier versions and their new names (a file using one is rejected naming the new).
struct RenamedKey {
  const char* old_name;
  const char* new_name;
};
const std::vector<RenamedKey>& renamedConfigKeys();

// YAML text of values: shortest text that reads back to the same value (floats keep a ".0").
std::string formatValue(double v);
std::string formatValue(float v);
std::string formatValue(int v);
std::string formatValue(std::uint64_t v);
std::string formatValue(bool v);
std::string formatValue(const std::string& v);  // plain when YAML reads it back as is, else quoted
std::string formatValue(const std::vector<int>& v);  // flow sequence "[0, 1]"

template <typename F>
ConfigKey number(std::string name, F field, double lo, double hi, std::string unit,
                 std::string doc) {
  using T = std::remove_cvref_t<decltype(field(std::declval<RunConfig&>()))>;
  static_assert(std::is_same_v<T, int> || std::is_same_v<T, float> || std::is_same_v<T, double>);
  ConfigKey k{std::move(name), std::move(unit), "", std::move(doc), {}, {}};
  if constexpr (std::is_same_v<T, int>) {
    k.range = formatValue(static_cast<int>(lo)) + ".." + formatValue(static_cast<int>(hi));
    k.read = [field, lo, hi](ConfigReader& r, const std::string& key, RunConfig& c) {
      return r.read(key, field(c), static_cast<int>(lo), static_cast<int>(hi));
    };
  } else {
    // Ranges in the shortest text of their double value, "1e-06" rather than "1.0e-06".
    auto text = [](double x) {
      char buf[32];
      return std::string(buf, std::to_chars(buf, buf + sizeof buf, x).ptr);
    };
    k.range = text(lo) + ".." + text(hi);
    k.read = [field, lo, hi](ConfigReader& r, const std::string& key, RunConfig& c) {
      return r.read(key, field(c), lo, hi);
    };
  }
  k.value = [field](const RunConfig& c) { return formatValue(field(c)); };
  return k;
}

// A key whose value is a plain YAML scalar of type T: field(c) must yield a T&.
template <typename T, typename F>
ConfigKey plain(std::string name, F field, std::string range, std::string doc) {
  ConfigKey k{std::move(name), "", std::move(range), std::move(doc), {}, {}};
  k.read = [field](ConfigReader& r, const std::string& key, RunConfig& c) {
    T& v = field(c);
    return r.read(key, v);
  };
  k.value = [field](const RunConfig& c) { return formatValue(field(c)); };
  return k;
}

template <typename F>
ConfigKey flag(std::string name, F field, std::string doc) {
  return plain<bool>(std::move(name), field, "", std::move(doc));
}

template <typename F>
ConfigKey text(std::string name, F field, std::string doc) {
  return plain<std::string>(std::move(name), field, "", std::move(doc));
}

template <typename F>
ConfigKey unsignedInt(std::string name, F field, std::string doc) {
  return plain<std::uint64_t>(std::move(name), field, "0..2^64-1", std::move(doc));
}

template <typename F, typename E, std::size_t N>
ConfigKey choice(std::string name, F field, const EnumNames<E, N>& names, std::string doc) {
  ConfigKey k{std::move(name), "", nameList(names), std::move(doc), {}, {}};
  k.read = [field, names](ConfigReader& r, const std::string& key, RunConfig& c) {
    E& v = field(c);
    std::string s = nameOf(names, v);
    std::vector<std::string> allowed;
    for (const auto& n : names) allowed.emplace_back(n.first);
    if (Status st = r.read(key, s, allowed); !st) return st;
    parseName(names, s, v);
    return Status::ok();
  };
  k.value = [field, names](const RunConfig& c) { return std::string(nameOf(names, field(c))); };
  return k;
}

}  // namespace svslam::config
