#pragma once
// The few YAML values svslam reads from calibration files it does not own (EuRoC sensor.yaml):
// a flow-style number list "key: [a, b, ...]", optionally nested under a parent key.
#include <string>
#include <vector>

#include "core/status.hpp"

namespace svslam::drivers {

// Numbers of the first "[ ... ]" after `key:` (searched after `parent:` when parent is not
// empty) in `text`. `what` names the file in errors. Non-finite values are an error.
Result<std::vector<double>> yamlNumberList(const std::string& text, const std::string& parent,
                                           const std::string& key, const std::string& what);

// The whole file as a string, or notFound naming it.
Result<std::string> readTextFile(const std::string& path);

}  // namespace svslam::drivers
