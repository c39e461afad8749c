// Image files as the kitti:/euroc: sources and the disparity tools read them: loadGrey (any
// format OpenCV decodes), loadMask and loadDisparity (.png). The loaders decode with cv::imread
// on a path (image_io.cpp says why), so the bytes go through a temporary file.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "drivers/files/file_bytes.hpp"
#include "drivers/files/image_io.hpp"

namespace {

// A folder of this process under the temporary directory, removed at exit.
struct ScratchFile {
  std::filesystem::path dir = std::filesystem::temp_directory_path() /
                              ("svslam_fuzz_image_" + std::to_string(::getpid()));
  std::string path = (dir / "input.png").string();
  ScratchFile() { std::filesystem::create_directories(dir); }
  ~ScratchFile() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static ScratchFile scratch;
  using namespace svslam::drivers;
  if (!writeFileAtomically(scratch.path, data, size)) return 0;
  (void)loadGrey(scratch.path);
  (void)loadMask(scratch.path);
  (void)loadDisparity(scratch.path, 256.0);
  return 0;
}
