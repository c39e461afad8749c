#include "pipeline/config/yaml_config.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace svslam::config {

ConfigReader::ConfigReader() : root_(YAML::NodeType::Map), name_("(defaults)") {}

Status ConfigReader::index(const YAML::Node& n, const std::string& prefix, int depth) {
  // An alias inside the map it names ("a: &x {b: *x}") makes the tree infinitely deep.
  if (depth > kMaxDepth)
    return Status::invalidArgument(name_ + ": maps nested more than " +
                                   std::to_string(kMaxDepth) +
                                   " deep (an alias inside its own anchor?) at '" + prefix + "'");
  for (const auto& kv : n) {
    const std::string where = prefix.empty() ? "the top level" : "'" + prefix + "'";
    if (!kv.first.IsScalar())
      return Status::invalidArgument(name_ + ": a key under " + where + " is not a plain name");
    const std::string path = prefix.empty() ? kv.first.Scalar() : prefix + "." + kv.first.Scalar();
    if (!keys_.emplace(path, kv.second).second)
      return Status::invalidArgument(name_ + ": duplicate key '" + path + "'");
    if (keys_.size() > kMaxKeys)
      return Status::invalidArgument(name_ + ": more than " + std::to_string(kMaxKeys) + " keys");
    if (kv.second.IsMap()) SVSLAM_TRY(index(kv.second, path, depth + 1));
  }
  return Status::ok();
}

Result<ConfigReader> ConfigReader::fromString(const std::string& text, const std::string& name) {
  ConfigReader r;
  r.name_ = name;
  try {
    r.root_ = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    return Status::invalidArgument(name + ": not valid YAML: " + e.what());
  }
  if (r.root_.IsNull()) r.root_ = YAML::Node(YAML::NodeType::Map);
  if (!r.root_.IsMap()) return Status::invalidArgument(name + ": the top level must be a map");
  if (Status s = r.index(r.root_, "", 0); !s) return s;
  return r;
}

Result<ConfigReader> ConfigReader::fromFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    return Status::invalidArgument("configuration file '" + path + "' is a directory");
  std::ifstream f(path, std::ios::binary);
  if (!f) return Status::notFound("cannot open configuration file '" + path + "'");
  std::ostringstream ss;
  ss << f.rdbuf();
  if (f.bad()) return Status::ioError("cannot read configuration file '" + path + "'");
  return fromString(ss.str(), path);
}

YAML::Node ConfigReader::find(const std::string& key) const {
  const auto it = keys_.find(key);
  return it == keys_.end() ? YAML::Node(YAML::NodeType::Undefined) : it->second;
}

bool ConfigReader::has(const std::string& key) const { return find(key).IsDefined(); }

Status ConfigReader::error(const std::string& key, const std::string& what) const {
  return Status::invalidArgument(name_ + ": key '" + key + "' " + what);
}

template <typename T>
void ConfigReader::assign(const std::string& key, T& v, const T& x) {
  if (!(v == x)) changed_.insert(key);
  v = x;
}

Status ConfigReader::readNumber(const std::string& key, bool& present, double& x, double min_value,
                                double max_value) {
  const YAML::Node n = find(key);
  used_.insert(key);
  present = n.IsDefined();
  if (!present) return Status::ok();
  if (!n.IsScalar() || !YAML::convert<double>::decode(n, x) || !std::isfinite(x))
    return error(key, "must be a finite number (got '" + (n.IsScalar() ? n.Scalar() : "?") + "')");
  if (x < min_value || x > max_value) {
    std::ostringstream ss;
    ss << "= " << x << " is out of range [" << min_value << ", " << max_value << "]";
    return error(key, ss.str());
  }
  return Status::ok();
}

Status ConfigReader::read(const std::string& key, double& v, double min_value, double max_value) {
  bool present = false;
  double x = 0;
  if (Status s = readNumber(key, present, x, min_value, max_value); !s) return s;
  if (present) assign(key, v, x);
  return Status::ok();
}

Status ConfigReader::read(const std::string& key, float& v, double min_value, double max_value) {
  bool present = false;
  double x = 0;
  if (Status s = readNumber(key, present, x, min_value, max_value); !s) return s;
  if (present) assign(key, v, static_cast<float>(x));
  return Status::ok();
}

Status ConfigReader::read(const std::string& key, int& v, int min_value, int max_value) {
  const YAML::Node n = find(key);
  used_.insert(key);
  if (!n.IsDefined()) return Status::ok();
  long long x = 0;
  if (!n.IsScalar() || !YAML::convert<long long>::decode(n, x))
    return error(key, "must be an integer (got '" + (n.IsScalar() ? n.Scalar() : "?") + "')");
  if (x < min_value || x > max_value)
    return error(key, "= " + std::to_string(x) + " is out of range [" + std::to_string(min_value) +
                          ", " + std::to_string(max_value) + "]");
  assign(key, v, static_cast<int>(x));
  return Status::ok();
}

Status ConfigReader::read(const std::string& key, std::uint64_t& v) {
  const YAML::Node n = find(key);
  used_.insert(key);
  if (!n.IsDefined()) return Status::ok();
  unsigned long long x = 0;
  if (!n.IsScalar() || n.Scalar().empty() || n.Scalar()[0] == '-' ||
      !YAML::convert<unsigned long long>::decode(n, x))
    return error(key, "must be a non-negative integer");
  assign(key, v, static_cast<std::uint64_t>(x));
  return Status::ok();
}

Status ConfigReader::read(const std::string& key, bool& v) {
  const YAML::Node n = find(key);
  used_.insert(key);
  if (!n.IsDefined()) return Status::ok();
  bool x = false;
  if (!n.IsScalar() || !YAML::convert<bool>::decode(n, x))
    return error(key, "must be true or false");
  assign(key, v, x);
  return Status::ok();
}

Status ConfigReader::read(const std::string& key, std::string& v,
                          const std::vector<std::string>& allowed) {
  const YAML::Node n = find(key);
  used_.insert(key);
  if (!n.IsDefined()) return Status::ok();
  if (!n.IsScalar()) return error(key, "must be a string");
  const std::string x = n.Scalar();
  if (!allowed.empty()) {
    bool ok = false;
    std::string list;
    for (const auto& a : allowed) {
      ok = ok || a == x;
      list += (list.empty() ? "" : ", ") + a;
    }
    if (!ok) return error(key, "= '" + x + "' is not one of: " + list);
  }
  assign(key, v, x);
  return Status::ok();
}

Status ConfigReader::read(const std::string& key, std::vector<double>& v) {
  const YAML::Node n = find(key);
  used_.insert(key);
  if (!n.IsDefined()) return Status::ok();
  if (!n.IsSequence()) return error(key, "must be a list of numbers");
  std::vector<double> x;
  for (const auto& e : n) {
    double d = 0;
    if (!e.IsScalar() || !YAML::convert<double>::decode(e, d) || !std::isfinite(d))
      return error(key, "must be a list of finite numbers");
    x.push_back(d);
  }
  assign(key, v, x);
  return Status::ok();
}

namespace {
// The first leaf key path under `n` (prefix `prefix`) that is not in `used`.
bool firstUnused(const YAML::Node& n, const std::string& prefix, const std::set<std::string>& used,
                 std::string& out) {
  if (!prefix.empty() && used.count(prefix)) return false;
  if (!n.IsMap()) {
    out = prefix;
    return true;
  }
  for (const auto& kv : n) {
    const std::string k = kv.first.Scalar();
    const std::string path = prefix.empty() ? k : prefix + "." + k;
    if (firstUnused(kv.second, path, used, out)) return true;
  }
  return false;
}
}  // namespace

Status ConfigReader::finish() const {
  std::string unused;
  if (!firstUnused(root_, "", used_, unused)) return Status::ok();
  // A value where a section of keys is expected ("detector: 5"): say so, not "unknown key".
  const std::string section = unused + ".";
  const auto it = used_.lower_bound(section);
  if (it != used_.end() && it->compare(0, section.size(), section) == 0)
    return Status::invalidArgument(name_ + ": key '" + unused +
                                   "' must be a mapping of keys (e.g. '" + *it +
                                   "'), not a single value or a list");
  return Status::invalidArgument(name_ + ": unknown key '" + unused + "'");
}

}  // namespace svslam::config
