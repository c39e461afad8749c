#pragma once
// JsonObject: one flat JSON object with keys in insertion order, for the CLI's stdout.
// Non-finite numbers are written as null (JSON has no NaN or infinity); strings are escaped
// with jsonEscape.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace svslam::cli {

class JsonObject {
 public:
  JsonObject& add(const std::string& key, const std::string& value);
  JsonObject& add(const std::string& key, const char* value);
  JsonObject& add(const std::string& key, double value, int decimals = 4);
  JsonObject& add(const std::string& key, std::int64_t value);
  JsonObject& add(const std::string& key, int value) {
    return add(key, static_cast<std::int64_t>(value));
  }
  JsonObject& add(const std::string& key, bool value);
  JsonObject& addRaw(const std::string& key, const std::string& json);  // nested object/array
  std::string str() const;

 private:
  std::vector<std::pair<std::string, std::string>> fields_;
};

// `s` as a JSON string literal (quoted, escaped). Bytes that are not valid UTF-8 (a file name
// in another encoding) each become U+FFFD, so the output is always valid JSON.
std::string jsonEscape(const std::string& s);

}  // namespace svslam::cli
