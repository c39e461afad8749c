#include "stereo/sigma_model.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace svslam {

SigmaModel SigmaModel::defaultCensus() {
  // Fitted with `svslam fit-sigma --bins 12` (census 9x7, window 9x9, uniqueness 10, LR check)
  // on the non-occluded pixels of Middlebury v2 tsukuba, venus, teddy, cones and Middlebury 2006
  // aloe, at most 100000 pixels per scene. Leave-one-scene-out coverage of one sigma: tsukuba
  // 0.70, venus 0.81, teddy 0.67, cones 0.65, aloe 0.51 (mean 0.67); see docs/stereo.md.
  SigmaModel m;
  m.curvature = {2.39506f, 5.51852f, 7.7037f,  9.62963f, 11.5062f, 13.3704f,
                 15.3086f, 17.4074f, 19.7654f, 22.6296f, 26.5309f, 33.2346f};
  m.sigma_px = {0.651512f, 0.479123f, 0.376785f, 0.301034f, 0.235232f, 0.201859f,
                0.183502f, 0.17292f,  0.16217f,  0.156315f, 0.147289f, 0.13488f};
  return m;
}

SigmaModel SigmaModel::defaultZnccPoints() {
  // Fitted with `svslam fit-sigma --matcher points --bins 8` (default corners, ZNCC 9x9, the
  // matcher's default tests and Gauss-Newton sub-pixel refinement) on the non-occluded pixels of
  // Middlebury v2 tsukuba, venus, teddy, cones and Middlebury 2006 aloe: 1391 matches with
  // ground truth, coverage 0.69 on them. Leave-one-scene-out coverage of one sigma: tsukuba
  // 0.59, venus 0.96, teddy 0.67, cones 0.77, aloe 0.42 (mean 0.68); see docs/stereo.md.
  SigmaModel m;
  m.curvature = {0.127105f, 0.197839f, 0.246208f, 0.293465f,
                 0.358619f, 0.436536f, 0.551564f, 0.833914f};
  m.sigma_px = {0.474449f, 0.341778f, 0.341778f, 0.321068f,
                0.295921f, 0.259769f, 0.179389f, 0.135022f};
  return m;
}

float SigmaModel::sigmaFor(float kappa) const {
  if (curvature.empty()) return 1.0f;
  if (!(kappa > curvature.front())) return sigma_px.front();
  if (kappa >= curvature.back()) return sigma_px.back();
  auto it = std::upper_bound(curvature.begin(), curvature.end(), kappa);
  const std::size_t j = static_cast<std::size_t>(it - curvature.begin());
  const float t = (kappa - curvature[j - 1]) / (curvature[j] - curvature[j - 1]);
  return sigma_px[j - 1] + t * (sigma_px[j] - sigma_px[j - 1]);
}

Status SigmaModel::validate() const {
  if (curvature.empty() || curvature.size() != sigma_px.size())
    return Status::invalidArgument(
        "sigma model: curvature and sigma tables must be non-empty and of equal length");
  for (std::size_t i = 0; i < curvature.size(); ++i) {
    if (!std::isfinite(curvature[i]) || !std::isfinite(sigma_px[i]) || !(sigma_px[i] > 0.0f))
      return Status::invalidArgument("sigma model: knots must be finite with sigma > 0");
    if (i > 0 && !(curvature[i] > curvature[i - 1]))
      return Status::invalidArgument("sigma model: curvature knots must be strictly increasing");
    if (i > 0 && sigma_px[i] > sigma_px[i - 1])
      return Status::invalidArgument("sigma model: sigma must not increase with curvature");
  }
  return Status::ok();
}

Result<SigmaModel> fitSigmaModel(const std::vector<float>& kappa, const std::vector<float>& abs_err,
                                 int bins) {
  if (kappa.size() != abs_err.size())
    return Status::invalidArgument("fitSigmaModel: size mismatch");
  if (bins < 1) return Status::invalidArgument("fitSigmaModel: bins must be >= 1");
  const std::size_t n = kappa.size();
  if (n < static_cast<std::size_t>(bins) * 20)
    return Status::invalidArgument("fitSigmaModel: fewer than 20 samples per bin");
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return kappa[a] < kappa[b]; });
  std::vector<double> knot_k, knot_s, weight;
  for (int b = 0; b < bins; ++b) {
    const std::size_t lo = n * static_cast<std::size_t>(b) / static_cast<std::size_t>(bins);
    const std::size_t hi = n * static_cast<std::size_t>(b + 1) / static_cast<std::size_t>(bins);
    std::vector<float> errs;
    errs.reserve(hi - lo);
    for (std::size_t j = lo; j < hi; ++j) errs.push_back(abs_err[order[j]]);
    const std::size_t q = std::min(
        errs.size() - 1,
        static_cast<std::size_t>(std::ceil(0.6827 * static_cast<double>(errs.size()))) - 1);
    std::nth_element(errs.begin(), errs.begin() + static_cast<std::ptrdiff_t>(q), errs.end());
    const double k_med = kappa[order[(lo + hi) / 2]];
    const double s = std::max(1e-3, static_cast<double>(errs[q]));
    if (!knot_k.empty() && !(k_med > knot_k.back())) {
      // Equal kappa medians (heavily quantised costs): merge into the previous knot.
      knot_s.back() = (knot_s.back() * weight.back() + s * static_cast<double>(hi - lo)) /
                      (weight.back() + static_cast<double>(hi - lo));
      weight.back() += static_cast<double>(hi - lo);
      continue;
    }
    knot_k.push_back(k_med);
    knot_s.push_back(s);
    weight.push_back(static_cast<double>(hi - lo));
  }
  // Pool adjacent violators: enforce non-increasing sigma, weighted by bin sizes.
  std::vector<double> val, w;
  std::vector<std::size_t> count;
  for (std::size_t i = 0; i < knot_s.size(); ++i) {
    val.push_back(knot_s[i]);
    w.push_back(weight[i]);
    count.push_back(1);
    while (val.size() > 1 && val[val.size() - 2] < val.back()) {
      const double nw = w[w.size() - 2] + w.back();
      const double nv = (val[val.size() - 2] * w[w.size() - 2] + val.back() * w.back()) / nw;
      const std::size_t nc = count[count.size() - 2] + count.back();
      val.pop_back();
      w.pop_back();
      count.pop_back();
      val.back() = nv;
      w.back() = nw;
      count.back() = nc;
    }
  }
  SigmaModel m;
  std::size_t k = 0;
  for (std::size_t g = 0; g < val.size(); ++g)
    for (std::size_t c = 0; c < count[g]; ++c, ++k) {
      m.curvature.push_back(static_cast<float>(knot_k[k]));
      m.sigma_px.push_back(static_cast<float>(val[g]));
    }
  if (Status s = m.validate(); !s) return s;
  return m;
}

double sigmaCoverage(const SigmaModel& model, const std::vector<float>& kappa,
                     const std::vector<float>& abs_err) {
  if (kappa.empty()) return 0.0;
  std::size_t inside = 0;
  for (std::size_t i = 0; i < kappa.size(); ++i)
    if (abs_err[i] <= model.sigmaFor(kappa[i])) ++inside;
  return static_cast<double>(inside) / static_cast<double>(kappa.size());
}

}  // namespace svslam
