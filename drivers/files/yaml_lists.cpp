#include "drivers/files/yaml_lists.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace svslam::drivers {

Result<std::string> readTextFile(const std::string& path) {
  std::ifstream f(path);
  if (!f) return Status::notFound("cannot open " + path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

Result<std::vector<double>> yamlNumberList(const std::string& text, const std::string& parent,
                                           const std::string& key, const std::string& what) {
  std::size_t from = 0;
  if (!parent.empty()) {
    from = text.find(parent + ":");
    if (from == std::string::npos) return Status::corruptData(what + ": no '" + parent + "' entry");
  }
  const auto k = text.find(key + ":", from);
  if (k == std::string::npos) return Status::corruptData(what + ": no '" + key + "' entry");
  const auto open = text.find('[', k);
  const auto close = open == std::string::npos ? std::string::npos : text.find(']', open);
  if (open == std::string::npos || close == std::string::npos)
    return Status::corruptData(what + ": '" + key + "' is not a [ ... ] list");
  std::string list = text.substr(open + 1, close - open - 1);
  std::replace(list.begin(), list.end(), ',', ' ');
  std::istringstream s(list);
  std::vector<double> v;
  std::string tok;
  while (s >> tok) {
    char* end = nullptr;
    const double d = std::strtod(tok.c_str(), &end);
    if (end == tok.c_str() || *end != '\0' || !std::isfinite(d))
      return Status::corruptData(what + ": '" + key + "' holds '" + tok + "', not a finite number");
    v.push_back(d);
  }
  return v;
}

}  // namespace svslam::drivers
