// The text files of the kitti: and euroc: layouts parsed from their content
// (drivers/datasets/dataset_files.hpp); the fuzz corpora replay the odd inputs.
#include "drivers/datasets/dataset_files.hpp"

#include <gtest/gtest.h>

namespace svslam::drivers {
namespace {

const char* kSensor =
    "T_BS:\n  data: [1,0,0,0.1, 0,1,0,0, 0,0,1,0, 0,0,0,1]\nresolution: [RES]\n"
    "intrinsics: [400, 401, 320, 240]\ndistortion_coefficients: [0.1, 0, 0, 0]\n";

std::string sensor(const std::string& res) {
  std::string s = kSensor;
  return s.replace(s.find("RES"), 3, res);
}

TEST(DatasetFiles, EurocSensor) {
  auto s = parseEurocSensor(sensor("640, 480"), "sensor.yaml");
  ASSERT_TRUE(s) << s.status().message();
  EXPECT_EQ(s->width, 640);
  EXPECT_EQ(s->height, 480);
  EXPECT_EQ(s->intrinsics[1], 401.0);
  EXPECT_EQ(s->distortion[0], 0.1);
  EXPECT_EQ(s->T_BS.translation().x(), 0.1);
}

// A resolution out of int's range was converted before it was checked (undefined behaviour,
// found with fuzz_euroc_sensor): now an error naming the file, as are fractions and zeros.
TEST(DatasetFiles, EurocResolutionOutOfRange) {
  for (const char* res : {"1e300, 480", "640, -1e300", "0, 480", "640.5, 480", "65537, 1"}) {
    auto s = parseEurocSensor(sensor(res), "sensor.yaml");
    ASSERT_FALSE(s) << res;
    EXPECT_EQ(s.status().code(), StatusCode::kCorruptData) << res;
    EXPECT_NE(s.status().message().find("sensor.yaml: resolution"), std::string::npos);
  }
}

TEST(DatasetFiles, EurocDataCsv) {
  auto l = parseEurocDataCsv("#timestamp [ns],filename\r\n10,a.png\r\n20,b.png \n", "data.csv");
  ASSERT_TRUE(l) << l.status().message();
  EXPECT_EQ(l->t_ns, (std::vector<TimeNs>{10, 20}));
  EXPECT_EQ(l->names, (std::vector<std::string>{"a.png", "b.png"}));
  EXPECT_FALSE(parseEurocDataCsv("x,a.png\n", "data.csv"));
  EXPECT_FALSE(parseEurocDataCsv("# only a comment\n", "data.csv"));
}

TEST(DatasetFiles, KittiCalibrationAndTimes) {
  auto c = parseKittiCalibration(
      "P0: 700 0 600 0 0 700 180 0 0 0 1 0\nP1: 700 0 600 -350 0 700 180 0 0 0 1 0\n",
      "calib.txt");
  ASSERT_TRUE(c) << c.status().message();
  EXPECT_EQ(c->f_px, 700.0);
  EXPECT_EQ(c->baseline_m, 0.5);
  EXPECT_FALSE(parseKittiCalibration("P0: 700 0 600 0 0 700 180 0 0 0 1 0\n", "calib.txt"));
  auto t = parseKittiTimes("0\n0.1\n\n0.2\n", "times.txt");
  ASSERT_TRUE(t) << t.status().message();
  EXPECT_EQ(t->size(), 3u);
  EXPECT_FALSE(parseKittiTimes("0.1\n0.1\n", "times.txt"));
}

}  // namespace
}  // namespace svslam::drivers
