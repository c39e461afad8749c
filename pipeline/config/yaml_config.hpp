#pragma once
// ConfigReader: strict reading of a YAML configuration file. Keys are dotted paths into nested
// maps ("stereo_match.min_zncc"). Each read() leaves the target untouched when the key is
// absent, and fails with a message naming the key on a wrong type or an out-of-range value.
// finish() fails on the first key of the file that no read() asked for (a typo, a key of an
// older version), so no setting is silently ignored. A key given twice in one map is an error.
// The file's key paths are indexed once when it is loaded (at most kMaxKeys), so a read costs
// a map lookup whatever the size of the file.
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/status.hpp"

// Returns the Status of `expr` from the enclosing function when it is an error (the key
// readers of the run configuration chain many reads).
#define SVSLAM_TRY(expr)                    \
  do {                                      \
    if (Status s_ = (expr); !s_) return s_; \
  } while (0)

namespace svslam::config {

class ConfigReader {
 public:
  // An empty configuration (every key absent).
  ConfigReader();
  static Result<ConfigReader> fromFile(const std::string& path);
  static Result<ConfigReader> fromString(const std::string& text, const std::string& name);
  static constexpr std::size_t kMaxKeys = 100000;  // key paths in a file (aliases expanded)
  static constexpr int kMaxDepth = 64;  // levels of nested maps (a self-referencing alias: error)

  Status read(const std::string& key, double& v, double min_value, double max_value);
  Status read(const std::string& key, float& v, double min_value, double max_value);
  Status read(const std::string& key, int& v, int min_value, int max_value);
  Status read(const std::string& key, std::uint64_t& v);
  Status read(const std::string& key, bool& v);
  // A string, optionally restricted to `allowed` (empty = any).
  Status read(const std::string& key, std::string& v, const std::vector<std::string>& allowed = {});
  // A sequence of numbers.
  Status read(const std::string& key, std::vector<double>& v);

  bool has(const std::string& key) const;
  // Keys of the file whose value differed from the target's value before the read (read into
  // defaults: the keys that change a default), in key order.
  const std::set<std::string>& changedKeys() const { return changed_; }
  // The first key present in the file and never read, as an error; ok when none.
  Status finish() const;
  const std::string& name() const { return name_; }

 private:
  YAML::Node find(const std::string& key) const;  // undefined node when absent
  // Indexes the key paths under `n` (a map, `depth` levels down) into keys_; error on a
  // duplicate key or deeper than kMaxDepth.
  Status index(const YAML::Node& n, const std::string& prefix, int depth);
  Status error(const std::string& key, const std::string& what) const;
  // The number at `key` checked against [min_value, max_value]; present = false when absent.
  Status readNumber(const std::string& key, bool& present, double& x, double min_value,
                    double max_value);
  // v = x, noting `key` in changed_ when the value differs.
  template <typename T>
  void assign(const std::string& key, T& v, const T& x);
  YAML::Node root_;
  std::map<std::string, YAML::Node> keys_;  // every key path of the file ("a.b.c") -> its value
  std::string name_;
  std::set<std::string> used_;
  std::set<std::string> changed_;
};

}  // namespace svslam::config
