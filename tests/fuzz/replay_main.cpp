// Replays a corpus through a fuzz harness without libFuzzer (the GCC build's fuzz_replay_<name>
// tests): every regular file of the folders (or the files) given on the command line is passed
// to LLVMFuzzerTestOneInput once. A crash, a sanitizer report or an abort fails the test; an
// empty corpus is an error, so the test cannot pass by replaying nothing.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  for (int i = 1; i < argc; ++i) {
    if (fs::is_directory(argv[i])) {
      for (const auto& e : fs::directory_iterator(argv[i]))
        if (e.is_regular_file()) files.push_back(e.path());
    } else if (fs::is_regular_file(argv[i])) {
      files.emplace_back(argv[i]);
    } else {
      std::fprintf(stderr, "no such corpus file or folder: %s\n", argv[i]);
      return 2;
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "no corpus file given\n");
    return 2;
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                  std::istreambuf_iterator<char>());
    if (!in.eof() && in.fail()) {
      std::fprintf(stderr, "cannot read %s\n", f.c_str());
      return 2;
    }
    // A heap copy of exactly the file's size, so that ASan sees reads past the end; an empty
    // input is a valid pointer and size 0, as libFuzzer passes it.
    std::vector<std::uint8_t> input(bytes.begin(), bytes.end());
    static std::uint8_t no_byte = 0;
    LLVMFuzzerTestOneInput(input.empty() ? &no_byte : input.data(), input.size());
  }
  std::printf("replayed %zu inputs\n", files.size());
  return 0;
}
