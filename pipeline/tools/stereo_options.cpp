#include "pipeline/tools/stereo_options.hpp"

#include <fstream>
#include <sstream>

namespace svslam::cli {

void addStereoOptions(ArgParser& p) {
  p.addOption("min-disp", "M", "smallest disparity searched, px (>= 0)", "0");
  p.addOption("method", "census|sad", "matching cost: census (Hamming) or sad (8-bit intensities)",
              "census");
  p.addOption("window", "WxH", "aggregation window, odd sides <= 31", "9x9");
  p.addOption("census", "WxH", "census window, odd sides >= 3, at most 64 neighbours", "9x7");
  p.addOption("prefilter", "none|mean|xsobel", "SAD prefilter (as OpenCV BM)", "xsobel");
  p.addOption("prefilter-cap", "N", "SAD prefilter clip, grey levels 1..63", "31");
  p.addOption("prefilter-size", "N", "SAD mean-removal window side, odd 3..21", "9");
  p.addOption("uniqueness", "PCT", "best cost must beat the second best by PCT percent (0 = off)",
              "10");
  p.addOption("texture", "T", "minimum mean |dI/dx| over the window, grey levels (0 = off)", "0");
  p.addFlag("no-lr-check", "disable reverse correlation (left-right consistency)");
  p.addOption("lr-max-diff", "N", "allowed |d_left - d_right| in the reverse correlation, px", "1");
  p.addFlag("no-subpixel", "integer disparities (no parabola fit)");
  p.addOption("backend", "auto|scalar|avx2|avx512|neon", "SIMD kernels", "auto");
  p.addOption("threads", "T", "threads used inside the stage (1..64)", "1");
  p.addOption("stripes", "S", "row stripes (tasks); default 4 x threads, 1 when threads = 1");
  p.addOption("sigma-model", "FILE",
              "curvature -> sigma_d table: lines 'kappa sigma_px' (default: built-in fit)");
}

Result<SigmaModel> loadSigmaModel(const std::string& path) {
  std::ifstream f(path);
  if (!f) return Status::notFound("cannot open sigma model file " + path);
  SigmaModel m;
  std::string line;
  int line_no = 0;
  while (std::getline(f, line)) {
    ++line_no;
    if (auto h = line.find('#'); h != std::string::npos) line = line.substr(0, h);
    std::istringstream s(line);
    float k, sg;
    if (!(s >> k)) continue;
    std::string rest;
    if (!(s >> sg) || (s >> rest))
      return Status::corruptData(path + ":" + std::to_string(line_no) +
                                 ": expected 'kappa sigma_px'");
    m.curvature.push_back(k);
    m.sigma_px.push_back(sg);
  }
  if (Status st = m.validate(); !st) return Status::corruptData(path + ": " + st.message());
  return m;
}

Result<DenseStereoParams> stereoParamsFromArgs(const ArgParser& p, int max_disp) {
  DenseStereoParams sp;
  sp.max_disp = max_disp;
  auto min_disp = p.getInt("min-disp", 0, 100000);
  if (!min_disp) return min_disp.status();
  sp.min_disp = *min_disp;
  if (!parseMatchingCost(p.get("method"), sp.cost))
    return Status::invalidArgument("--method: unknown method '" + p.get("method") +
                                   "' (use census or sad)");
  if (Status s = p.getSize("window", sp.window_w, sp.window_h); !s) return s;
  if (Status s = p.getSize("census", sp.census_w, sp.census_h); !s) return s;
  if (!parseSadPrefilter(p.get("prefilter"), sp.prefilter))
    return Status::invalidArgument("--prefilter: unknown prefilter '" + p.get("prefilter") +
                                   "' (use none, mean or xsobel)");
  auto cap = p.getInt("prefilter-cap", 1, 63);
  if (!cap) return cap.status();
  sp.prefilter_cap = *cap;
  auto pf_size = p.getInt("prefilter-size", 3, 21);
  if (!pf_size) return pf_size.status();
  sp.prefilter_size = *pf_size;
  auto uniq = p.getInt("uniqueness", 0, 100);
  if (!uniq) return uniq.status();
  sp.uniqueness_pct = *uniq;
  auto tex = p.getDouble("texture");
  if (!tex) return tex.status();
  if (*tex < 0) return Status::invalidArgument("--texture must be >= 0");
  sp.texture_threshold = static_cast<float>(*tex);
  sp.lr_check = !p.flag("no-lr-check");
  auto lr = p.getInt("lr-max-diff", 0, 1000);
  if (!lr) return lr.status();
  sp.lr_max_diff = *lr;
  sp.subpixel = !p.flag("no-subpixel");
  if (!simd::parseBackend(p.get("backend").c_str(), sp.backend))
    return Status::invalidArgument("--backend: unknown backend '" + p.get("backend") + "'");
  auto threads = p.getInt("threads", 1, 64);
  if (!threads) return threads.status();
  if (p.has("stripes")) {
    auto st = p.getInt("stripes", 1, 256);
    if (!st) return st.status();
    sp.num_stripes = *st;
  } else {
    sp.num_stripes = *threads == 1 ? 1 : 4 * *threads;
  }
  if (p.has("sigma-model")) {
    auto m = loadSigmaModel(p.get("sigma-model"));
    if (!m) return m.status();
    sp.sigma_model = *m;
  }
  if (Status s = sp.validate(); !s) return s;
  return sp;
}

}  // namespace svslam::cli
