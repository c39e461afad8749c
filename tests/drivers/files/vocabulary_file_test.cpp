// Vocabulary files: save / load round trip and errors naming the path.
#include "drivers/files/vocabulary_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>

namespace fs = std::filesystem;

namespace svslam::drivers {
namespace {

class VocabularyFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("svslam_voc_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static BinaryVocabulary trained() {
    std::mt19937_64 rng(1);
    std::vector<std::vector<OrbDescriptor>> images(6, std::vector<OrbDescriptor>(100));
    for (auto& im : images)
      for (auto& d : im)
        for (auto& w : d.words) w = rng();
    VocabularyParams p;
    p.depth = 2;
    return BinaryVocabulary::train(images, p).value();
  }
  fs::path dir_;
};

TEST_F(VocabularyFile, RoundTrip) {
  const BinaryVocabulary voc = trained();
  const std::string path = (dir_ / "voc.svvoc").string();
  ASSERT_TRUE(saveVocabulary(path, voc).isOk());
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  auto back = loadVocabulary(path);
  ASSERT_TRUE(back.isOk()) << back.status().message();
  EXPECT_EQ(back->serialize(), voc.serialize());
}

TEST_F(VocabularyFile, Errors) {
  const std::string missing = (dir_ / "missing.svvoc").string();
  auto r = loadVocabulary(missing);
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound);
  EXPECT_NE(r.status().message().find(missing), std::string::npos);

  const std::string garbage = (dir_ / "garbage.svvoc").string();
  std::ofstream(garbage) << "this is not a vocabulary at all, just some text";
  r = loadVocabulary(garbage);
  EXPECT_EQ(r.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(r.status().message().find(garbage), std::string::npos) << r.status().message();

  const std::string truncated = (dir_ / "truncated.svvoc").string();
  const auto bytes = trained().serialize();
  std::ofstream(truncated, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size() / 2));
  EXPECT_EQ(loadVocabulary(truncated).status().code(), StatusCode::kCorruptData);

  EXPECT_EQ(saveVocabulary((dir_ / "no_dir" / "v.svvoc").string(), trained()).code(),
            StatusCode::kIoError);
}

}  // namespace
}  // namespace svslam::drivers
