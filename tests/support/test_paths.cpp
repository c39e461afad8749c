// The absolute paths behind test_paths.hpp, from this object's compile definitions.
#include "test_paths.hpp"

namespace svslam_test {
const char* dataDirPath() { return SVSLAM_TEST_DATA_DIR; }
const char* cliPath() { return SVSLAM_TEST_CLI; }
const char* sourceDirPath() { return SVSLAM_TEST_SOURCE_DIR; }
}  // namespace svslam_test
