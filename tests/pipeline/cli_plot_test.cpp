// svslam plot end to end: a short synthetic run, then its pictures: every SVG is well-formed XML,
// the trajectory is one path with one vertex per pose of trajectory_tum.txt (the ground truth
// another), the PNGs decode at the requested size; bad run folders fail with a message.
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_helpers.hpp"

namespace fs = std::filesystem;
using svslam::test::slurp;

namespace {

// A small well-formedness check of XML 1.0 as svslam writes it: one root element, tags nested
// and closed, attributes quoted and not repeated, entity references among the five predefined or
// numeric, no '<' or bare '&' in text. Returns "" when well-formed, else the problem.
std::string xmlProblem(const std::string& s) {
  std::vector<std::string> stack;
  std::size_t i = 0;
  int roots = 0;
  auto isName = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == ':' ||
           c == '.';
  };
  auto checkText = [](const std::string& t) -> std::string {
    for (std::size_t k = 0; k < t.size(); ++k) {
      if (t[k] == '<') return "'<' in text";
      if (t[k] != '&') continue;
      const std::size_t semi = t.find(';', k);
      if (semi == std::string::npos) return "bare '&'";
      const std::string ent = t.substr(k + 1, semi - k - 1);
      if (ent != "amp" && ent != "lt" && ent != "gt" && ent != "quot" && ent != "apos" &&
          !(ent.size() > 1 && ent[0] == '#'))
        return "unknown entity &" + ent + ";";
    }
    return "";
  };
  if (s.rfind("<?xml", 0) == 0) {
    i = s.find("?>");
    if (i == std::string::npos) return "unterminated XML declaration";
    i += 2;
  }
  while (i < s.size()) {
    const std::size_t lt = s.find('<', i);
    const std::string text = s.substr(i, lt == std::string::npos ? std::string::npos : lt - i);
    if (auto p = checkText(text); !p.empty()) return p;
    if (stack.empty() && text.find_first_not_of(" \t\r\n") != std::string::npos)
      return "text outside the root element";
    if (lt == std::string::npos) break;
    if (s.compare(lt, 4, "<!--") == 0) {
      const std::size_t end = s.find("-->", lt);
      if (end == std::string::npos) return "unterminated comment";
      i = end + 3;
      continue;
    }
    const bool closing = lt + 1 < s.size() && s[lt + 1] == '/';
    std::size_t k = lt + (closing ? 2 : 1);
    std::string name;
    while (k < s.size() && isName(s[k])) name += s[k++];
    if (name.empty()) return "tag without name at byte " + std::to_string(lt);
    if (closing) {
      while (k < s.size() && std::isspace(static_cast<unsigned char>(s[k]))) ++k;
      if (k >= s.size() || s[k] != '>') return "bad end tag </" + name;
      if (stack.empty() || stack.back() != name) return "mismatched </" + name + ">";
      stack.pop_back();
      i = k + 1;
      continue;
    }
    std::vector<std::string> attrs;
    for (;;) {
      while (k < s.size() && std::isspace(static_cast<unsigned char>(s[k]))) ++k;
      if (k >= s.size()) return "unterminated tag <" + name;
      if (s[k] == '>' || s.compare(k, 2, "/>") == 0) break;
      std::string attr;
      while (k < s.size() && isName(s[k])) attr += s[k++];
      if (attr.empty()) return "bad attribute in <" + name;
      for (const auto& a : attrs)
        if (a == attr) return "repeated attribute " + attr + " in <" + name;
      attrs.push_back(attr);
      if (k >= s.size() || s[k] != '=') return "attribute " + attr + " without value";
      ++k;
      if (k >= s.size() || (s[k] != '"' && s[k] != '\'')) return "unquoted attribute " + attr;
      const char q = s[k];
      const std::size_t end = s.find(q, k + 1);
      if (end == std::string::npos) return "unterminated attribute " + attr;
      if (auto p = checkText(s.substr(k + 1, end - k - 1)); !p.empty()) return attr + ": " + p;
      k = end + 1;
    }
    if (stack.empty() && ++roots > 1) return "more than one root element";
    if (s[k] == '>') {
      stack.push_back(name);
      i = k + 1;
    } else {
      i = k + 2;
    }
  }
  if (!stack.empty()) return "unclosed <" + stack.back() + ">";
  if (roots != 1) return "no root element";
  return "";
}

// The vertices of the `d` attribute of the <path> with id `id`: the number of coordinate pairs,
// -1 when there is no such path.
int pathVertices(const std::string& svg, const std::string& id) {
  const std::size_t at = svg.find("<path id=\"" + id + "\"");
  if (at == std::string::npos) return -1;
  const std::size_t d = svg.find(" d=\"", at);
  const std::string data = svg.substr(d + 4, svg.find('"', d + 4) - d - 4);
  std::istringstream ss(data);
  std::string word;
  int numbers = 0;
  while (ss >> word)
    if (word != "M" && word != "L" && word != "Z") ++numbers;
  return numbers % 2 == 0 ? numbers / 2 : -2;
}

int lines(const fs::path& p) {
  std::ifstream f(p);
  std::string line;
  int n = 0;
  while (std::getline(f, line))
    if (!line.empty()) ++n;
  return n;
}

class CliPlot : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    run_ = fs::temp_directory_path() / ("svslam_cli_plot_run_" + std::to_string(::getpid()));
    fs::remove_all(run_);
    fs::create_directories(run_);
    run_code_ = svslam::test::runSvslam(
        "run --source synthetic:width=320,height=240,frames=12 --out " + run_.string(),
        run_ / "run_out.txt", run_ / "run_err.txt");
  }
  static void TearDownTestSuite() { fs::remove_all(run_); }
  void SetUp() override {
    ASSERT_EQ(run_code_, 0) << slurp(run_ / "run_err.txt");
    dir_ = svslam::test::freshTestDir("svslam_cli_plot_");
  }
  void TearDown() override { fs::remove_all(dir_); }
  int plot(const std::string& args, std::string& out, std::string& err) const {
    const int code = svslam::test::runSvslam("plot " + args, dir_ / "out.txt", dir_ / "err.txt");
    out = slurp(dir_ / "out.txt");
    err = slurp(dir_ / "err.txt");
    return code;
  }
  void expectError(const std::string& args, const std::string& needle) const {
    std::string out, err;
    const int code = plot(args, out, err);
    EXPECT_TRUE(code == 1 || code == 2) << args << " exited " << code << "\n" << err;
    EXPECT_NE(err.find(needle), std::string::npos) << args << "\nstderr: " << err;
    EXPECT_TRUE(out.empty()) << out;
  }
  // A copy of the run folder, to spoil.
  fs::path copyRun() const {
    const fs::path copy = dir_ / "run";
    fs::copy(run_, copy);
    return copy;
  }
  static fs::path run_;
  static int run_code_;
  fs::path dir_;
};
fs::path CliPlot::run_;
int CliPlot::run_code_ = -1;

TEST_F(CliPlot, WritesWellFormedSvgAndPngWithOneVertexPerPose) {
  std::string out, err;
  const fs::path pics = dir_ / "pics";
  ASSERT_EQ(plot("--run " + run_.string() + " --out " + pics.string(), out, err), 0) << err;
  EXPECT_NE(out.find("\"poses\": 12"), std::string::npos) << out;
  EXPECT_NE(out.find("\"skipped\": []"), std::string::npos) << out;
  for (const char* name : {"trajectory_top", "altitude", "landmarks", "latency"}) {
    const std::string svg = slurp(pics / (std::string(name) + ".svg"));
    ASSERT_FALSE(svg.empty()) << name;
    EXPECT_EQ(xmlProblem(svg), "") << name;
    EXPECT_NE(out.find(std::string(name) + ".png"), std::string::npos) << out;
    const cv::Mat png = cv::imread((pics / (std::string(name) + ".png")).string());
    ASSERT_FALSE(png.empty()) << name;
    EXPECT_EQ(png.cols, 800);
    EXPECT_EQ(png.rows, 600);
  }
  const int poses = lines(run_ / "trajectory_tum.txt");
  ASSERT_EQ(poses, 12);
  const std::string top = slurp(pics / "trajectory_top.svg");
  EXPECT_EQ(pathVertices(top, "trajectory"), poses);
  EXPECT_EQ(pathVertices(top, "ground_truth"), lines(run_ / "groundtruth_kitti.txt"));
  EXPECT_NE(top.find("id=\"ellipse_"), std::string::npos);  // ekf mode: covariances
  EXPECT_EQ(pathVertices(slurp(pics / "altitude.svg"), "altitude"), poses);
  EXPECT_EQ(pathVertices(slurp(pics / "landmarks.svg"), "trajectory"), poses);
}

TEST_F(CliPlot, SizeGroundTruthAndAlignmentOptions) {
  std::string out, err;
  ASSERT_EQ(plot("--run " + run_.string() + " --out " + dir_.string() +
                     " --size 640x480 --ground-truth none --gravity 0,1,0 --ellipse-every 5",
                 out, err),
            0)
      << err;
  EXPECT_NE(out.find("\"ground_truth\": \"none\""), std::string::npos) << out;
  EXPECT_NE(out.find("\"top_view_axes\": \"x,z\""), std::string::npos) << out;
  const std::string top = slurp(dir_ / "trajectory_top.svg");
  EXPECT_EQ(pathVertices(top, "ground_truth"), -1);
  EXPECT_NE(top.find("id=\"ellipse_5\""), std::string::npos);
  EXPECT_EQ(top.find("id=\"ellipse_4\""), std::string::npos);
  const cv::Mat png = cv::imread((dir_ / "altitude.png").string());
  EXPECT_EQ(png.cols, 640);
  EXPECT_EQ(png.rows, 480);
  ASSERT_EQ(plot("--run " + run_.string() + " --out " + dir_.string() + " --align se3", out, err),
            0)
      << err;
  EXPECT_EQ(pathVertices(slurp(dir_ / "trajectory_top.svg"), "ground_truth"), 12);
}

TEST_F(CliPlot, MissingOptionalFilesAreSkippedWithAReason) {
  const fs::path run = copyRun();
  fs::remove(run / "landmarks.ply");
  fs::remove(run / "pose_covariance.txt");
  fs::remove(run / "stats.json");
  std::string out, err;
  ASSERT_EQ(plot("--run " + run.string(), out, err), 0) << err;
  EXPECT_NE(out.find("no landmarks.ply"), std::string::npos) << out;
  EXPECT_NE(out.find("no stats.json"), std::string::npos) << out;
  EXPECT_NE(out.find("\"ellipses\": 0"), std::string::npos) << out;
  EXPECT_NE(out.find("no pose_covariance.txt"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists(run / "trajectory_top.png"));
  EXPECT_FALSE(fs::exists(run / "landmarks.png"));
}

TEST_F(CliPlot, BadInputFailsWithAMessage) {
  expectError("--run " + (dir_ / "nowhere").string(), "does not exist");
  expectError("", "--run");
  expectError("--run " + run_.string() + " --align sim3", "--align");
  expectError("--run " + run_.string() + " --gravity 0,0,0", "--gravity");
  expectError("--run " + run_.string() + " --gravity 0,1", "--gravity");
  expectError("--run " + run_.string() + " --size 100x100", "--size");
  expectError("--run " + run_.string() + " --ground-truth " + (dir_ / "gt.txt").string(), "gt.txt");

  const fs::path run = copyRun();
  const std::string r = "--run " + run.string() + " --out " + (dir_ / "pics").string();
  {  // NaN in the covariance
    std::string cov = slurp(run / "pose_covariance.txt");
    cov.replace(cov.find(' '), 1, " nan ");
    std::ofstream(run / "pose_covariance.txt") << cov;
    expectError(r, "pose_covariance.txt:1");
  }
  std::ofstream(run / "pose_covariance.txt") << "1 2 3\n";
  expectError(r, "pose_covariance.txt:1");
  fs::remove(run / "pose_covariance.txt");
  std::ofstream(run / "stats.json") << "{\"frames\": 3, \"stage_ms\": {\"a\": ";
  expectError(r, "stats.json");
  fs::remove(run / "stats.json");
  std::ofstream(run / "landmarks.ply") << "ply\nformat ascii 1.0\nelement vertex 5\n"
                                          "property float x\nproperty float y\nend_header\n1 2\n";
  expectError(r, "landmarks.ply");
  fs::remove(run / "landmarks.ply");
  std::ofstream(run / "trajectory_tum.txt") << "";
  expectError(r, "trajectory_tum.txt");
  std::ofstream(run / "trajectory_tum.txt") << "0 1 2 3\n";
  expectError(r, "trajectory_tum.txt");
  fs::remove(run / "trajectory_tum.txt");
  expectError(r, "trajectory_tum.txt");
}

TEST(XmlCheck, RejectsBrokenXml) {
  EXPECT_EQ(xmlProblem("<?xml version=\"1.0\"?>\n<a x=\"1\"><b/>t &amp; u</a>\n"), "");
  EXPECT_NE(xmlProblem("<a><b></a></b>"), "");
  EXPECT_NE(xmlProblem("<a x=1/>"), "");
  EXPECT_NE(xmlProblem("<a>x & y</a>"), "");
  EXPECT_NE(xmlProblem("<a x=\"1\" x=\"2\"/>"), "");
  EXPECT_NE(xmlProblem("<a/><b/>"), "");
  EXPECT_NE(xmlProblem("<a>"), "");
  EXPECT_EQ(pathVertices("<path id=\"t\" d=\"M 1 2 L 3 4 L 5 6\"/>", "t"), 3);
}

}  // namespace
