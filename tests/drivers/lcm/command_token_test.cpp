// readCommandToken: the token of a file readable by its owner alone; errors naming the file
// when it is missing, empty, or open to group or others.
#include "drivers/lcm/command_token.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace svslam::drivers {
namespace {

namespace fs = std::filesystem;

class CommandToken : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("svslam_token_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text, mode_t mode) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    ::chmod(p.c_str(), mode);
    return p.string();
  }
  fs::path dir_;
};

TEST_F(CommandToken, ReadsTheTokenWithoutTrailingNewline) {
  auto t = readCommandToken(write("ok", "abc123-token\n", 0600));
  ASSERT_TRUE(t.isOk()) << t.status().message();
  EXPECT_EQ(*t, "abc123-token");
  auto r = readCommandToken(write("ro", "read-only token", 0400));
  ASSERT_TRUE(r.isOk()) << r.status().message();
  EXPECT_EQ(*r, "read-only token");
}

TEST_F(CommandToken, MissingFileIsAnErrorNamingIt) {
  const std::string path = (dir_ / "absent").string();
  auto t = readCommandToken(path);
  ASSERT_FALSE(t.isOk());
  EXPECT_NE(t.status().message().find(path), std::string::npos) << t.status().message();
  EXPECT_NE(t.status().message().find("cannot open"), std::string::npos);
}

TEST_F(CommandToken, EmptyFileIsAnError) {
  for (const char* text : {"", "\n", "  \n"}) {
    const std::string path = write("empty", text, 0600);
    auto t = readCommandToken(path);
    ASSERT_FALSE(t.isOk()) << '"' << text << '"';
    EXPECT_NE(t.status().message().find(path), std::string::npos);
    EXPECT_NE(t.status().message().find("empty"), std::string::npos) << t.status().message();
  }
}

TEST_F(CommandToken, FileOpenToGroupOrOthersIsAnError) {
  for (mode_t mode : {0640, 0604, 0644, 0660, 0610}) {
    const std::string path = write("open", "token", mode);
    auto t = readCommandToken(path);
    ASSERT_FALSE(t.isOk()) << std::oct << mode;
    EXPECT_NE(t.status().message().find(path), std::string::npos);
    EXPECT_NE(t.status().message().find("readable by the service alone"), std::string::npos)
        << t.status().message();
  }
}

TEST_F(CommandToken, DirectoryIsNotAToken) {
  fs::create_directories(dir_ / "d");
  ::chmod((dir_ / "d").c_str(), 0700);
  EXPECT_FALSE(readCommandToken((dir_ / "d").string()).isOk());
  EXPECT_FALSE(readCommandToken("").isOk());
}

}  // namespace
}  // namespace svslam::drivers
