#include "drivers/files/run_files.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <utility>

#include "drivers/files/file_bytes.hpp"
#include "drivers/files/yaml_lists.hpp"

namespace svslam::drivers {

namespace {

bool blank(const std::string& line) { return line.find_first_not_of(" \t\r") == std::string::npos; }

Status lineError(const std::string& path, int line, const std::string& what) {
  return Status::corruptData(path + ":" + std::to_string(line) + ": " + what);
}

// A JSON value, enough of it to walk stats.json: objects keep their key order. The literal
// tokens nan / -nan / inf that printf writes for non-finite numbers are read as NaN.
struct Json {
  enum class Type { kNull, kBool, kNumber, kString, kArray, kObject } type = Type::kNull;
  double number = NAN;
  std::string text;
  // Object members as two parallel vectors: a std::pair holding the incomplete Json is
  // rejected by clang with libstdc++ (the fuzz build), a vector of it is not.
  std::vector<std::string> keys;  // object
  std::vector<Json> values;       // object, values[i] under keys[i]
  std::vector<Json> items;        // array
  const Json* find(const std::string& key) const {
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (keys[i] == key) return &values[i];
    return nullptr;
  }
};

class JsonParser {
 public:
  explicit JsonParser(const std::string& s) : s_(s) {}
  bool parse(Json& out) {
    if (!value(out, 0)) return false;
    skip();
    return pos_ == s_.size();
  }
  std::size_t pos() const { return pos_; }

 private:
  void skip() {
    while (pos_ < s_.size() && std::strchr(" \t\r\n", s_[pos_]) != nullptr) ++pos_;
  }
  bool literal(const char* word) {
    const std::size_t n = std::strlen(word);
    if (s_.compare(pos_, n, word) != 0) return false;
    pos_ += n;
    return true;
  }
  bool string(std::string& out) {
    if (pos_ >= s_.size() || s_[pos_] != '"') return false;
    ++pos_;
    while (pos_ < s_.size() && s_[pos_] != '"') {
      if (s_[pos_] == '\\') {
        if (++pos_ >= s_.size()) return false;
        const char c = s_[pos_];
        if (c == 'u') {  // kept as '?': stage names are ASCII
          if (pos_ + 4 >= s_.size()) return false;
          pos_ += 4;
          out += '?';
        } else {
          out += c == 'n'   ? '\n'
                 : c == 't' ? '\t'
                 : c == 'r' ? '\r'
                 : c == 'b' ? '\b'
                 : c == 'f' ? '\f'
                            : c;
        }
      } else {
        out += s_[pos_];
      }
      ++pos_;
    }
    if (pos_ >= s_.size()) return false;
    ++pos_;
    return true;
  }
  bool value(Json& v, int depth) {
    if (depth > 64) return false;
    skip();
    if (pos_ >= s_.size()) return false;
    const char c = s_[pos_];
    if (c == '{' || c == '[') {
      const bool obj = c == '{';
      v.type = obj ? Json::Type::kObject : Json::Type::kArray;
      ++pos_;
      skip();
      if (pos_ < s_.size() && s_[pos_] == (obj ? '}' : ']')) return ++pos_, true;
      for (;;) {
        Json item;
        std::string key;
        if (obj) {
          skip();
          if (!string(key)) return false;
          skip();
          if (pos_ >= s_.size() || s_[pos_++] != ':') return false;
        }
        if (!value(item, depth + 1)) return false;
        if (obj) {
          v.keys.push_back(std::move(key));
          v.values.push_back(std::move(item));
        } else {
          v.items.push_back(std::move(item));
        }
        skip();
        if (pos_ >= s_.size()) return false;
        if (s_[pos_] == ',') {
          ++pos_;
          continue;
        }
        if (s_[pos_] == (obj ? '}' : ']')) return ++pos_, true;
        return false;
      }
    }
    if (c == '"') {
      v.type = Json::Type::kString;
      return string(v.text);
    }
    if (literal("true") || literal("false")) {
      v.type = Json::Type::kBool;
      return true;
    }
    if (literal("null") || literal("nan") || literal("-nan") || literal("inf") || literal("-inf")) {
      v.type = Json::Type::kNull;
      return true;
    }
    const char* begin = s_.c_str() + pos_;
    char* end = nullptr;
    v.number = std::strtod(begin, &end);
    if (end == begin) return false;
    v.type = Json::Type::kNumber;
    pos_ += static_cast<std::size_t>(end - begin);
    return true;
  }

  const std::string& s_;
  std::size_t pos_ = 0;
};

double numberOr(const Json& obj, const char* key, double fallback) {
  const Json* v = obj.find(key);
  return v && v->type == Json::Type::kNumber ? v->number : fallback;
}

}  // namespace

Result<std::vector<PoseCovariance>> readPoseCovariances(const std::string& path) {
  auto text = readTextFile(path);
  if (!text) return text.status();
  std::istringstream lines(*text);
  std::string line;
  std::vector<PoseCovariance> out;
  int n = 0;
  while (std::getline(lines, line)) {
    ++n;
    if (blank(line)) continue;
    std::istringstream ls(line);
    PoseCovariance P;
    for (int k = 0; k < 36; ++k) {
      std::string word;
      if (!(ls >> word))
        return lineError(path, n, "expected 36 numbers, found " + std::to_string(k));
      char* end = nullptr;
      const double x = std::strtod(word.c_str(), &end);
      if (end == word.c_str() || *end != '\0')
        return lineError(path, n, "'" + word + "' is not a number");
      if (!std::isfinite(x))
        return lineError(path, n, "non-finite covariance entry '" + word + "'");
      P(k / 6, k % 6) = x;
    }
    std::string extra;
    if (ls >> extra) return lineError(path, n, "more than 36 numbers");
    out.push_back(P);
  }
  return out;
}

Result<std::vector<LandmarkPoint>> readLandmarksPly(const std::string& path) {
  auto text = readTextFile(path);
  if (!text) return text.status();
  std::istringstream lines(*text);
  std::string line;
  int n = 0;
  if (!std::getline(lines, line) || line.rfind("ply", 0) != 0)
    return lineError(path, 1, "not a PLY file (no 'ply' magic)");
  ++n;
  long long count = -1;
  bool in_vertex = false, ascii = false, vertex_first = true;
  std::vector<std::string> props;
  for (;;) {
    if (!std::getline(lines, line)) return lineError(path, n, "header has no end_header");
    ++n;
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "end_header") break;
    if (word == "format") {
      std::string fmt;
      ls >> fmt;
      ascii = fmt == "ascii";
    } else if (word == "element") {
      std::string name;
      long long k = -1;
      ls >> name >> k;
      in_vertex = name == "vertex";
      if (in_vertex) {
        if (k < 0) return lineError(path, n, "bad vertex count");
        count = k;
      } else if (count < 0) {
        vertex_first = false;
      }
    } else if (word == "property" && in_vertex) {
      std::string type, name;
      ls >> type >> name;
      if (type == "list") return lineError(path, n, "list properties of vertices are not read");
      props.push_back(name);
    }
  }
  if (!ascii) return Status::corruptData(path + ": only ASCII PLY is read");
  if (count < 0 || !vertex_first)
    return Status::corruptData(path + ": no 'vertex' element (first) in the header");
  int ix = -1, iy = -1, iz = -1, iactive = -1;
  for (int i = 0; i < static_cast<int>(props.size()); ++i) {
    if (props[i] == "x") ix = i;
    if (props[i] == "y") iy = i;
    if (props[i] == "z") iz = i;
    if (props[i] == "active") iactive = i;
  }
  if (ix < 0 || iy < 0 || iz < 0)
    return Status::corruptData(path + ": the vertices have no x, y and z properties");
  std::vector<LandmarkPoint> out;
  std::vector<double> vals(props.size());
  while (static_cast<long long>(out.size()) < count) {
    if (!std::getline(lines, line))
      return Status::corruptData(path + ": " + std::to_string(out.size()) + " vertices of " +
                                 std::to_string(count) + " announced");
    ++n;
    std::istringstream ls(line);
    for (std::size_t k = 0; k < props.size(); ++k)
      if (!(ls >> vals[k]))
        return lineError(path, n, "expected " + std::to_string(props.size()) + " numbers");
    LandmarkPoint p;
    p.p_world = {vals[ix], vals[iy], vals[iz]};
    if (!p.p_world.allFinite()) return lineError(path, n, "non-finite landmark position");
    p.active = iactive >= 0 && vals[iactive] != 0;
    out.push_back(p);
  }
  return out;
}

Result<std::vector<StageTimeSummary>> readStageTimes(const std::string& stats_json_path) {
  auto text = readTextFile(stats_json_path);
  if (!text) return text.status();
  Json root;
  JsonParser parser(*text);
  if (!parser.parse(root))
    return Status::corruptData(stats_json_path + ": not valid JSON (near byte " +
                               std::to_string(parser.pos()) + ")");
  const Json* stages = root.find("stage_ms");
  if (root.type != Json::Type::kObject || !stages || stages->type != Json::Type::kObject)
    return Status::corruptData(stats_json_path + ": no \"stage_ms\" object");
  std::vector<StageTimeSummary> out;
  for (std::size_t i = 0; i < stages->keys.size(); ++i) {
    const std::string& name = stages->keys[i];
    const Json& v = stages->values[i];
    if (v.type != Json::Type::kObject) continue;
    StageTimeSummary s;
    s.stage = name;
    s.p50_ms = numberOr(v, "p50_ms", NAN);
    s.p99_ms = numberOr(v, "p99_ms", NAN);
    s.max_ms = numberOr(v, "max_ms", NAN);
    const double count = numberOr(v, "count", 0);
    s.count = std::isfinite(count) ? static_cast<std::int64_t>(std::clamp(count, 0.0, 1e15)) : 0;
    out.push_back(s);
  }
  return out;
}

Result<std::vector<double>> readLatencyLog(const std::string& path) {
  auto text = readTextFile(path);
  if (!text) return text.status();
  std::istringstream lines(*text);
  std::string line;
  std::vector<double> ms;
  int n = 0;
  while (std::getline(lines, line)) {
    ++n;
    if (blank(line) || line[line.find_first_not_of(" \t")] == '#') continue;
    std::istringstream ls(line);
    double seq = 0, v = 0;
    if (!(ls >> seq >> v) || !std::isfinite(v))
      return lineError(path, n, "expected 'seq ms' with a finite latency");
    ms.push_back(v);
  }
  return ms;
}

Status writePlotPng(const std::string& path, const cv::Mat& bgr) {
  if (bgr.empty() || bgr.type() != CV_8UC3)
    return Status::invalidArgument("cannot write " + path + ": not an 8-bit colour image");
  std::vector<unsigned char> buf;
  try {
    if (!cv::imencode(".png", bgr, buf, {cv::IMWRITE_PNG_COMPRESSION, 9}))
      return Status::ioError("cannot encode PNG for " + path);
  } catch (const std::exception& e) {
    return Status::ioError("cannot encode PNG for " + path + ": " + e.what());
  }
  return writeFileAtomically(path, buf.data(), buf.size());
}

Status writePlotText(const std::string& path, const std::string& text) {
  return writeFileAtomically(path, text.data(), text.size());
}

}  // namespace svslam::drivers
