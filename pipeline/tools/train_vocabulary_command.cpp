// svslam train-vocabulary: ORB descriptors of a set of images -> a bag-of-words vocabulary file
// (BinaryVocabulary, "SVVOC1") for loop closing.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <climits>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "drivers/files/image_io.hpp"
#include "drivers/files/vocabulary_file.hpp"
#include "drivers/source/stereo_source.hpp"
#include "loop/keyframe.hpp"
#include "features/orb_extractor.hpp"
#include "loop/binary_vocabulary.hpp"
#include "pipeline/cli/arg_parser.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/cli/json_writer.hpp"

namespace svslam::cli {
namespace {

namespace fs = std::filesystem;

bool isImageName(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* e : {".png", ".jpg", ".jpeg", ".pgm", ".ppm", ".bmp", ".tif", ".tiff"})
    if (ext == e) return true;
  return false;
}

// The images of a folder (image extensions, sorted by name) or of a list file (one path per
// line, relative to the list's folder; blank lines and lines starting with '#' skipped).
Status listImages(const std::string& where, std::vector<std::string>& out) {
  std::error_code ec;
  const fs::file_status st = fs::status(where, ec);
  if (!fs::exists(st)) return Status::notFound("--images: no such folder or list file: " + where);
  if (fs::is_directory(st)) {
    for (const auto& e : fs::directory_iterator(where, ec))
      if (e.is_regular_file(ec) && isImageName(e.path())) out.push_back(e.path().string());
    if (ec) return Status::ioError("--images: cannot list " + where + ": " + ec.message());
    std::sort(out.begin(), out.end());
  } else {
    std::ifstream in(where);
    if (!in) return Status::ioError("--images: cannot read the list " + where);
    const fs::path base = fs::path(where).parent_path();
    std::string line;
    while (std::getline(in, line)) {
      while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back())))
        line.pop_back();
      std::size_t b = 0;
      while (b < line.size() && std::isspace(static_cast<unsigned char>(line[b]))) ++b;
      line.erase(0, b);
      if (line.empty() || line[0] == '#') continue;
      const fs::path p(line);
      out.push_back(p.is_absolute() ? p.string() : (base / p).string());
    }
  }
  if (out.empty()) return Status::invalidArgument("--images: no image in " + where);
  return Status::ok();
}

}  // namespace

int runTrainVocabulary(const std::vector<std::string>& args) {
  ArgParser p("train-vocabulary",
              "Extracts ORB descriptors (the keyframes' ORB parameters) from every image (or the\n"
              "left images of a stereo source) and trains a\n"
              "bag-of-words vocabulary tree by hierarchical k-majority clustering (loop closing).\n"
              "Prints JSON: images, descriptors, words, bytes (of the file), extract_s, train_s.");
  p.addOption("images", "DIR|LIST",
              "folder of images (png, jpg, pgm, bmp, tif; sorted by name) or a text file with one "
              "image path per line (relative to the file's folder)",
              std::nullopt, false);
  p.addOption("source", "SPEC",
              "instead of --images: the left images of a stereo source (svslam run --source), e.g. "
              "synthetic:seed=99 (keep it apart from the data loops are evaluated on)",
              std::nullopt, false);
  p.addOption("frames", "N", "with --source: the first N frames, 1..100000", "100");
  p.addOption("out", "FILE", "vocabulary file to write (SVVOC1)", std::nullopt, true);
  p.addOption("branching", "K", "children per node, 2..255", "10");
  p.addOption("depth", "L", "levels below the root, 1..8", "4");
  p.addOption("max-iterations", "N", "k-medians rounds per node, 1..1000", "10");
  p.addOption("seed", "S", "seed of the k-means++ initialisation, 0..2147483647", "7");
  p.addOption("max-images", "N", "with --images: use at most N images, evenly spaced over the set (0 = all)", "0");
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("train-vocabulary", s); };
  VocabularyParams vp;
  auto k = p.getInt("branching", 2, 255);
  if (!k) return fail(k.status());
  auto l = p.getInt("depth", 1, 8);
  if (!l) return fail(l.status());
  auto it = p.getInt("max-iterations", 1, 1000);
  if (!it) return fail(it.status());
  auto seed = p.getInt("seed", 0, INT_MAX);
  if (!seed) return fail(seed.status());
  auto max_images = p.getInt("max-images", 0, INT_MAX);
  if (!max_images) return fail(max_images.status());
  vp.branching = *k;
  vp.depth = *l;
  vp.max_iterations = *it;
  vp.seed = static_cast<std::uint64_t>(*seed);

  auto frames = p.getInt("frames", 1, 100000);
  if (!frames) return fail(frames.status());
  if (p.has("images") == p.has("source"))
    return fail(Status::invalidArgument("give exactly one of --images and --source"));
  std::vector<std::string> paths;
  std::unique_ptr<drivers::StereoSource> source;
  if (p.has("source")) {
    auto src = drivers::openStereoSource(p.get("source"));
    if (!src) return fail(Status(src.status().code(), "--source: " + src.status().message()));
    source = std::move(*src);
    for (int i = 0; i < *frames; ++i) paths.push_back(p.get("source") + " frame " + std::to_string(i));
  } else if (Status s = listImages(p.get("images"), paths); !s) {
    return fail(s);
  }
  if (!source && *max_images > 0 && paths.size() > static_cast<std::size_t>(*max_images)) {
    std::vector<std::string> kept;
    const std::size_t n = paths.size(), m = static_cast<std::size_t>(*max_images);
    for (std::size_t i = 0; i < m; ++i) kept.push_back(paths[i * n / m]);
    paths.swap(kept);
  }

  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::vector<OrbDescriptor>> descriptors;
  std::vector<OrbKeypoint> keypoints;
  std::unique_ptr<OrbExtractor> orb;
  int orb_w = 0, orb_h = 0;
  std::size_t total = 0;
  drivers::StereoFrame frame;
  std::size_t used = 0;
  for (const std::string& path : paths) {
    Result<ImageU8> loaded = Status::invalidArgument("no image");
    ImageView<const std::uint8_t> view;
    if (source) {
      auto more = source->next(frame);  // the source reuses frame's buffers
      if (!more) return fail(Status(more.status().code(), path + ": " + more.status().message()));
      if (!*more) break;  // the source ended before --frames
      view = frame.left.cview();
    } else {
      loaded = drivers::loadGrey(path);
      if (!loaded) return fail(loaded.status());
      view = loaded->cview();
    }
    ++used;
    if (!orb || view.width != orb_w || view.height != orb_h) {
      orb_w = view.width;
      orb_h = view.height;
      orb = std::make_unique<OrbExtractor>(KeyframeParams::defaultOrb(), orb_w, orb_h);
      if (!orb->initStatus())
        return fail(Status(orb->initStatus().code(), path + ": " + orb->initStatus().message()));
    }
    descriptors.emplace_back();
    if (Status s = orb->process(view, keypoints, descriptors.back()); !s)
      return fail(Status(s.code(), path + ": " + s.message()));
    total += descriptors.back().size();
  }
  const auto t1 = std::chrono::steady_clock::now();
  auto voc = BinaryVocabulary::train(descriptors, vp);
  if (!voc) return fail(voc.status());
  const auto t2 = std::chrono::steady_clock::now();
  const std::string out = p.get("out");
  if (Status s = drivers::saveVocabulary(out, *voc); !s) return fail(s);
  std::error_code ec;
  const auto bytes = fs::file_size(out, ec);
  JsonObject j;
  j.add("images", static_cast<std::int64_t>(used))
      .add("descriptors", static_cast<std::int64_t>(total))
      .add("words", voc->numWords())
      .add("bytes", static_cast<std::int64_t>(ec ? 0 : bytes))
      .add("out", out)
      .add("extract_s", std::chrono::duration<double>(t1 - t0).count(), 3)
      .add("train_s", std::chrono::duration<double>(t2 - t1).count(), 3);
  std::printf("%s\n", j.str().c_str());
  return 0;
}

}  // namespace svslam::cli
