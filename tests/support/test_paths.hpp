// Where the tests find the shared data, the svslam executable and the source tree.
//
// The paths are compiled into one object (test_paths.cpp) instead of every test's command line, so
// the test objects do not depend on where the clone lives and a build cache (ccache, hashing paths
// relative to the clone) reuses them in a fresh clone. Every test gets these macros through the
// precompiled header, or through -include when precompiled headers are off.
#pragma once

namespace svslam_test {
// Folder of the shared evaluation data (may not exist: the tests that need it skip).
const char* dataDirPath();
// The built svslam executable, or "" when the CLI is not part of this build.
const char* cliPath();
// The source tree's root folder.
const char* sourceDirPath();
}  // namespace svslam_test

#define SVSLAM_DATA_DIR (::svslam_test::dataDirPath())
#define SVSLAM_CLI (::svslam_test::cliPath())
#define SVSLAM_SOURCE_DIR (::svslam_test::sourceDirPath())
