#pragma once
// ArgParser: the `--name value` / `--flag` command-line grammar of every svslam subcommand.
// Options are declared with their help text; parse() rejects unknown options, missing values and
// repeated options with a message naming the option; help() lists every option.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/status.hpp"

namespace svslam::cli {

class ArgParser {
 public:
  ArgParser(std::string command, std::string summary);

  // An option taking a value; `value_name` shows in the help ("FILE", "N", ...).
  void addOption(const std::string& name, const std::string& value_name, const std::string& help,
                 std::optional<std::string> default_value = std::nullopt, bool required = false);
  // A flag without value.
  void addFlag(const std::string& name, const std::string& help);

  // Parses argv-style words (without the program and subcommand names).
  Status parse(const std::vector<std::string>& args);

  bool helpRequested() const { return help_; }
  std::string help() const;

  bool has(const std::string& name) const;  // given on the command line, or has a default
  bool flag(const std::string& name) const;
  std::string get(const std::string& name) const;  // precondition: has(name)
  // Typed getters: an error names the option and the bad text.
  Result<int> getInt(const std::string& name, int min_value, int max_value) const;
  Result<double> getDouble(const std::string& name) const;
  // "WxH" with W, H in [1, 99] (odd when require_odd), or up to 8192 when !require_odd.
  Status getSize(const std::string& name, int& w, int& h, bool require_odd = true) const;

 private:
  struct Option {
    std::string name, value_name, help;
    std::optional<std::string> default_value;
    bool required = false;
    bool is_flag = false;
  };
  std::string command_, summary_;
  std::vector<Option> options_;
  std::map<std::string, std::string> values_;
  std::map<std::string, bool> flags_;
  bool help_ = false;
  const Option* find(const std::string& name) const;
};

// Parses a subcommand's words: returns an exit code to return right away (2 after printing the
// parse error, 0 after printing --help), or nothing when the command should run.
std::optional<int> parseCommandLine(ArgParser& p, const std::vector<std::string>& args);

// Prints "svslam <command>: <message>" on stderr and returns exit code 1.
int reportFailure(const std::string& command, const Status& s);

}  // namespace svslam::cli
