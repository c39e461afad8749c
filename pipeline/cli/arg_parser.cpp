#include "pipeline/cli/arg_parser.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace svslam::cli {

ArgParser::ArgParser(std::string command, std::string summary)
    : command_(std::move(command)), summary_(std::move(summary)) {}

void ArgParser::addOption(const std::string& name, const std::string& value_name,
                          const std::string& help, std::optional<std::string> default_value,
                          bool required) {
  options_.push_back({name, value_name, help, std::move(default_value), required, false});
}

void ArgParser::addFlag(const std::string& name, const std::string& help) {
  options_.push_back({name, "", help, std::nullopt, false, true});
}

const ArgParser::Option* ArgParser::find(const std::string& name) const {
  for (const auto& o : options_)
    if (o.name == name) return &o;
  return nullptr;
}

Status ArgParser::parse(const std::vector<std::string>& args) {
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h") {
      help_ = true;
      return Status::ok();
    }
    if (a.rfind("--", 0) != 0)
      return Status::invalidArgument(command_ + ": unexpected argument '" + a +
                                     "' (options start with --)");
    std::string name = a.substr(2);
    std::optional<std::string> inline_value;
    if (auto eq = name.find('='); eq != std::string::npos) {
      inline_value = name.substr(eq + 1);
      name = name.substr(0, eq);
    }
    const Option* o = find(name);
    if (o == nullptr)
      return Status::invalidArgument(command_ + ": unknown option --" + name + " (see --help)");
    if (values_.count(name) || flags_.count(name))
      return Status::invalidArgument(command_ + ": option --" + name + " given twice");
    if (o->is_flag) {
      if (inline_value)
        return Status::invalidArgument(command_ + ": --" + name + " takes no value");
      flags_[name] = true;
      continue;
    }
    if (inline_value) {
      values_[name] = *inline_value;
    } else {
      if (i + 1 >= args.size())
        return Status::invalidArgument(command_ + ": option --" + name + " needs a value " +
                                       o->value_name);
      values_[name] = args[++i];
    }
  }
  for (const auto& o : options_)
    if (o.required && !values_.count(o.name))
      return Status::invalidArgument(command_ + ": missing required option --" + o.name);
  return Status::ok();
}

std::string ArgParser::help() const {
  std::ostringstream s;
  s << "usage: svslam " << command_ << " [options]\n\n" << summary_ << "\n\noptions:\n";
  for (const auto& o : options_) {
    std::string head = "  --" + o.name + (o.is_flag ? "" : " " + o.value_name);
    s << head;
    if (head.size() < 28)
      s << std::string(28 - head.size(), ' ');
    else
      s << "\n" << std::string(28, ' ');
    s << o.help;
    if (o.required) s << " (required)";
    if (o.default_value) s << " [default: " << *o.default_value << "]";
    s << "\n";
  }
  s << "  --help                    print this help and exit\n";
  return s.str();
}

bool ArgParser::has(const std::string& name) const {
  if (values_.count(name)) return true;
  const Option* o = find(name);
  return o != nullptr && o->default_value.has_value();
}

bool ArgParser::flag(const std::string& name) const { return flags_.count(name) > 0; }

std::string ArgParser::get(const std::string& name) const {
  if (auto it = values_.find(name); it != values_.end()) return it->second;
  const Option* o = find(name);
  return o != nullptr && o->default_value ? *o->default_value : std::string();
}

Result<int> ArgParser::getInt(const std::string& name, int min_value, int max_value) const {
  const std::string v = get(name);
  errno = 0;
  char* end = nullptr;
  const long n = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || end == nullptr || *end != '\0' || errno != 0)
    return Status::invalidArgument("--" + name + ": '" + v + "' is not an integer");
  if (n < min_value || n > max_value)
    return Status::invalidArgument("--" + name + ": " + v + " is out of range [" +
                                   std::to_string(min_value) + ", " + std::to_string(max_value) +
                                   "]");
  return static_cast<int>(n);
}

Result<double> ArgParser::getDouble(const std::string& name) const {
  const std::string v = get(name);
  errno = 0;
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (v.empty() || end == nullptr || *end != '\0' || errno != 0 || !std::isfinite(d))
    return Status::invalidArgument("--" + name + ": '" + v + "' is not a finite number");
  return d;
}

Status ArgParser::getSize(const std::string& name, int& w, int& h, bool require_odd) const {
  const std::string v = get(name);
  const auto x = v.find('x');
  auto parse = [](const std::string& t, int& out) {
    if (t.empty() || t.size() > 9) return false;  // 9 digits fit an int
    for (char c : t)
      if (c < '0' || c > '9') return false;
    out = std::stoi(t);
    return true;
  };
  if (x == std::string::npos || !parse(v.substr(0, x), w) || !parse(v.substr(x + 1), h))
    return Status::invalidArgument("--" + name + ": '" + v + "' is not of the form WxH (e.g. 9x7)");
  const int max_side = require_odd ? 99 : 8192;
  if (w > max_side || h > max_side)
    return Status::invalidArgument("--" + name + ": " + v + " is too large (each side at most " +
                                   std::to_string(max_side) + ")");
  if (!require_odd) {
    if (w < 1 || h < 1)
      return Status::invalidArgument("--" + name + ": sides must be >= 1, got " + v);
    return Status::ok();
  }
  if (w < 1 || h < 1 || w % 2 == 0 || h % 2 == 0)
    return Status::invalidArgument("--" + name + ": window sides must be odd and >= 1, got " + v);
  return Status::ok();
}

std::optional<int> parseCommandLine(ArgParser& p, const std::vector<std::string>& args) {
  if (Status s = p.parse(args); !s) {
    std::fprintf(stderr, "svslam %s\n", s.message().c_str());
    return 2;
  }
  if (p.helpRequested()) {
    std::fputs(p.help().c_str(), stdout);
    return 0;
  }
  return std::nullopt;
}

int reportFailure(const std::string& command, const Status& s) {
  std::fprintf(stderr, "svslam %s: %s\n", command.c_str(), s.message().c_str());
  return 1;
}

}  // namespace svslam::cli
