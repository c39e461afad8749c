#pragma once
// Helpers of the tests that run the svslam executable through the shell.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "../core/test_files.hpp"

namespace svslam::test {

// The exit code in a wait status: the process's own, or 128 + the signal that ended it.
inline int exitCode(int status) {
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// Runs `command` with /bin/sh, its stdout into the file `out` and its stderr into `err`;
// returns its exit code.
inline int runShell(const std::string& command, const std::filesystem::path& out,
                    const std::filesystem::path& err) {
  const std::string cmd = command + " > " + out.string() + " 2> " + err.string();
  return exitCode(std::system(cmd.c_str()));
}

// `svslam <args>`, as runShell.
inline int runSvslam(const std::string& args, const std::filesystem::path& out,
                     const std::filesystem::path& err) {
  return runShell(std::string(SVSLAM_CLI) + " " + args, out, err);
}

}  // namespace svslam::test
