// svslam config: prints the documented configuration of `svslam run`.
#include <cstdio>
#include <string>
#include <vector>

#include "pipeline/cli/arg_parser.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/config/run_config.hpp"

namespace svslam::cli {

int runConfig(const std::vector<std::string>& args) {
  ArgParser p("config",
              "Prints the configuration file of `svslam run` with every key at its default value,\n"
              "section by section, each key with a comment giving its range or choices, unit and\n"
              "meaning (the file config/svslam.yaml is this output). Floating values print so\n"
              "that they read back exactly.");
  p.addFlag("defaults", "print the documented defaults file on stdout");
  if (auto code = parseCommandLine(p, args)) return *code;
  if (!p.flag("defaults")) {
    std::fprintf(stderr, "svslam config: nothing to do: use --defaults\n\n%s", p.help().c_str());
    return 2;
  }
  const std::string text = config::defaultsYaml();
  std::fwrite(text.data(), 1, text.size(), stdout);
  return 0;
}

}  // namespace svslam::cli
