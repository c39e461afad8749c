#include "features/orb_extractor.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

#include "features/fast_detector.hpp"

namespace svslam {
namespace {

// SplitMix64 (Steele, Lea & Flood 2014): a tiny generator with a fixed, platform-independent
// sequence, so the BRIEF pattern is the same everywhere for a given seed.
class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : s_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform() { return (static_cast<double>(next() >> 11) + 0.5) * 0x1.0p-53; }  // (0, 1)
  double gaussian() {  // Box-Muller, N(0, 1)
    const double u = uniform(), v = uniform();
    return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::numbers::pi * v);
  }

 private:
  std::uint64_t s_;
};

std::vector<std::array<std::int8_t, 4>> makePattern(std::uint64_t seed, int bits, int radius) {
  SplitMix64 rng(seed);
  const double sigma = (2 * radius + 1) / 5.0;
  auto point = [&](int& x, int& y) {
    do {
      x = static_cast<int>(std::lround(sigma * rng.gaussian()));
      y = static_cast<int>(std::lround(sigma * rng.gaussian()));
    } while (x * x + y * y > radius * radius);
  };
  std::vector<std::array<std::int8_t, 4>> pattern;
  while (static_cast<int>(pattern.size()) < bits) {
    int x1, y1, x2, y2;
    point(x1, y1);
    point(x2, y2);
    if (x1 == x2 && y1 == y2) continue;
    pattern.push_back({static_cast<std::int8_t>(x1), static_cast<std::int8_t>(y1),
                       static_cast<std::int8_t>(x2), static_cast<std::int8_t>(y2)});
  }
  return pattern;
}

std::vector<float> gaussianKernel(double sigma) {
  const int r = std::max(1, static_cast<int>(std::ceil(2.0 * sigma)));
  std::vector<float> k(static_cast<std::size_t>(2 * r + 1));
  double sum = 0;
  for (int i = -r; i <= r; ++i) sum += std::exp(-0.5 * i * i / (sigma * sigma));
  for (int i = -r; i <= r; ++i)
    k[static_cast<std::size_t>(i + r)] =
        static_cast<float>(std::exp(-0.5 * i * i / (sigma * sigma)) / sum);
  return k;
}

}  // namespace

int hammingDistance(const OrbDescriptor& a, const OrbDescriptor& b) {
  int n = 0;
  for (std::size_t i = 0; i < a.words.size(); ++i) n += std::popcount(a.words[i] ^ b.words[i]);
  return n;
}

Status OrbParams::validate() const {
  if (num_octaves < 1 || num_octaves > 4)
    return Status::invalidArgument("num_octaves must be in 1..4");
  if (fast_threshold < 1 || fast_threshold > 254)
    return Status::invalidArgument("fast_threshold must be in 1..254");
  if (orientation_radius_px < 3 || orientation_radius_px > OrbExtractor::kPatchRadiusPx)
    return Status::invalidArgument("orientation_radius_px must be in 3..15");
  if (!(blur_sigma_px >= 0.5 && blur_sigma_px <= 4))
    return Status::invalidArgument("blur_sigma_px must be in 0.5..4");
  if (angle_step_deg < 1 || angle_step_deg > 45 || 360 % angle_step_deg != 0)
    return Status::invalidArgument("angle_step_deg must be in 1..45 and divide 360");
  if (grid_cols < 1 || grid_rows < 1 || max_per_cell < 1)
    return Status::invalidArgument("grid_cols, grid_rows and max_per_cell must be >= 1");
  return Status::ok();
}

double OrbExtractor::layerScale(int k) {
  if (k < 0) return 2.0 / 3.0;
  return (k % 2 == 0 ? 1.0 : 1.5) * std::ldexp(1.0, k / 2);
}

ImageView<const std::uint8_t> OrbExtractor::layer(int k) const {
  if (k < 0 || k >= numLayers()) return {};
  return layers_[static_cast<std::size_t>(k)].image.cview();
}

OrbExtractor::OrbExtractor(const OrbParams& params, int width, int height)
    : params_(params), width_(width), height_(height) {
  init_status_ = params_.validate();
  if (!init_status_) return;
  if (width < 2 * kBorderPx + 1 || height < 2 * kBorderPx + 1 || width > 32768 || height > 32768) {
    init_status_ =
        Status::invalidArgument("image size out of the ORB extractor's range (33..32768)");
    return;
  }
  const int n = 2 * params_.num_octaves;
  // Area-resampling taps: target pixel j covers [j f, (j + 1) f) in source pixel edges
  // (f = source px per target px); weight of source pixel m = overlap with [m, m + 1) / f.
  auto taps = [](int src_n, int dst_n, double f) {
    std::vector<AreaTap> out(static_cast<std::size_t>(dst_n));
    for (int j = 0; j < dst_n; ++j) {
      const double lo = j * f, hi = (j + 1) * f;
      const int m0 = static_cast<int>(std::floor(lo));
      AreaTap& t = out[static_cast<std::size_t>(j)];
      for (int i = 0; i < 3; ++i) {
        const int m = m0 + i;
        const double overlap = std::max(0.0, std::min(hi, m + 1.0) - std::max(lo, 1.0 * m));
        t.k[static_cast<std::size_t>(i)] = std::min(m, src_n - 1);
        t.w[static_cast<std::size_t>(i)] = m < src_n ? static_cast<float>(overlap / f) : 0.0f;
      }
    }
    return out;
  };
  layers_.resize(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    Layer& l = layers_[static_cast<std::size_t>(k)];
    const int i = k / 2;
    const int w = k % 2 == 0 ? width >> i : (2 * width / 3) >> i;
    const int h = k % 2 == 0 ? height >> i : (2 * height / 3) >> i;
    if (w < 4 || h < 4) {
      init_status_ = Status::invalidArgument("image too small for num_octaves pyramid layers");
      layers_.clear();
      return;
    }
    l.scale = layerScale(k);
    l.source = k == 0 ? -1 : (k == 1 ? 0 : k - 2);
    for (ImageU8* im : {&l.image, &l.smoothed, &l.score}) im->resize(w, h);
    l.circle = fastOffsets16(l.score.stride());
    if (k > 0) {
      const Layer& s = layers_[static_cast<std::size_t>(l.source)];
      const double f = l.scale / s.scale;
      l.taps_x = taps(s.image.width(), w, f);
      l.taps_y = taps(s.image.height(), h, f);
    }
  }
  score58_.resize(width, height);
  circle8_ = fastOffsets8(score58_.stride());
  tmp_.resize(width, height);
  gauss_ = gaussianKernel(params_.blur_sigma_px);
  row_in_.resize(static_cast<std::size_t>(width) + gauss_.size());
  const int r = params_.orientation_radius_px;
  for (int v = 0; v <= r; ++v)
    disc_half_width_.push_back(static_cast<int>(std::floor(std::sqrt(1.0 * (r * r - v * v)))));
  pattern_ = makePattern(params_.pattern_seed, kBits, kPatchRadiusPx);
  const int bins = 360 / params_.angle_step_deg;
  rotated_.reserve(static_cast<std::size_t>(bins * kBits));
  for (int b = 0; b < bins; ++b) {
    const double th = b * params_.angle_step_deg * std::numbers::pi / 180.0;
    const double c = std::cos(th), s = std::sin(th);
    auto rot = [&](int x, int y, std::int8_t& xo, std::int8_t& yo) {
      xo = static_cast<std::int8_t>(std::lround(c * x - s * y));
      yo = static_cast<std::int8_t>(std::lround(s * x + c * y));
    };
    for (const auto& p : pattern_) {
      std::array<std::int8_t, 4> q{};
      rot(p[0], p[1], q[0], q[1]);
      rot(p[2], p[3], q[2], q[3]);
      rotated_.push_back(q);
    }
  }
  candidates_.reserve(4096);
}

void OrbExtractor::resampleLayer(int k) {
  Layer& d = layers_[static_cast<std::size_t>(k)];
  const Layer& s = layers_[static_cast<std::size_t>(d.source)];
  const int dw = d.image.width(), dh = d.image.height(), sh = s.image.height();
  for (int y = 0; y < sh; ++y) {  // horizontal: tmp_ is dw x sh
    const std::uint8_t* in = s.image.row(y);
    float* out = tmp_.row(y);
    for (int x = 0; x < dw; ++x) {
      const AreaTap& t = d.taps_x[static_cast<std::size_t>(x)];
      out[x] = t.w[0] * in[t.k[0]] + t.w[1] * in[t.k[1]] + t.w[2] * in[t.k[2]];
    }
  }
  for (int y = 0; y < dh; ++y) {  // vertical
    const AreaTap& t = d.taps_y[static_cast<std::size_t>(y)];
    const float *r0 = tmp_.row(t.k[0]), *r1 = tmp_.row(t.k[1]), *r2 = tmp_.row(t.k[2]);
    std::uint8_t* out = d.image.row(y);
    for (int x = 0; x < dw; ++x)
      out[x] = static_cast<std::uint8_t>(
          std::min(255.0f, t.w[0] * r0[x] + t.w[1] * r1[x] + t.w[2] * r2[x] + 0.5f));
  }
}

// Separable Gaussian with replicated borders: horizontal into tmp_, vertical into `smoothed`.
void OrbExtractor::smoothLayer(int k) {
  Layer& l = layers_[static_cast<std::size_t>(k)];
  const int w = l.image.width(), h = l.image.height();
  const int r = static_cast<int>(gauss_.size() / 2), taps = static_cast<int>(gauss_.size());
  float* pad = row_in_.data();
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* in = l.image.row(y);
    for (int i = 0; i < w + 2 * r; ++i) pad[i] = in[std::clamp(i - r, 0, w - 1)];
    float* out = tmp_.row(y);
    for (int x = 0; x < w; ++x) out[x] = 0;
    for (int t = 0; t < taps; ++t) {
      const float g = gauss_[static_cast<std::size_t>(t)];
      for (int x = 0; x < w; ++x) out[x] += g * pad[x + t];
    }
  }
  for (int y = 0; y < h; ++y) {
    float* acc = pad;
    for (int x = 0; x < w; ++x) acc[x] = 0;
    for (int t = 0; t < taps; ++t) {
      const float g = gauss_[static_cast<std::size_t>(t)];
      const float* in = tmp_.row(std::clamp(y + t - r, 0, h - 1));
      for (int x = 0; x < w; ++x) acc[x] += g * in[x];
    }
    std::uint8_t* out = l.smoothed.row(y);
    for (int x = 0; x < w; ++x) out[x] = static_cast<std::uint8_t>(std::min(255.0f, acc[x] + 0.5f));
  }
}

// Intensity centroid: angle of (m10, m01) over the disc of radius r around pixel (x, y).
float OrbExtractor::orientation(const Layer& l, int x, int y) const {
  const int r = params_.orientation_radius_px;
  long m01 = 0, m10 = 0;
  for (int v = -r; v <= r; ++v) {
    const std::uint8_t* row = l.image.row(y + v) + x;
    const int hw = disc_half_width_[static_cast<std::size_t>(std::abs(v))];
    long sum = 0, sum_u = 0;
    for (int u = -hw; u <= hw; ++u) {
      sum += row[u];
      sum_u += u * row[u];
    }
    m10 += sum_u;
    m01 += v * sum;
  }
  return static_cast<float>(std::atan2(static_cast<double>(m01), static_cast<double>(m10)));
}

OrbDescriptor OrbExtractor::describe(const Layer& l, int x, int y, float angle_rad) const {
  const int bins = 360 / params_.angle_step_deg;
  const double deg = angle_rad * 180.0 / std::numbers::pi;
  int bin = static_cast<int>(std::lround(deg / params_.angle_step_deg)) % bins;
  if (bin < 0) bin += bins;
  const auto* pairs = rotated_.data() + static_cast<std::ptrdiff_t>(bin) * kBits;
  const std::uint8_t* centre = l.smoothed.row(y) + x;
  const std::ptrdiff_t stride = l.smoothed.stride();
  OrbDescriptor d;
  for (int j = 0; j < kBits; ++j) {
    const auto& p = pairs[j];
    const bool bit = centre[p[1] * stride + p[0]] < centre[p[3] * stride + p[2]];
    d.words[static_cast<std::size_t>(j / 64)] |= static_cast<std::uint64_t>(bit) << (j % 64);
  }
  return d;
}

Status OrbExtractor::process(ImageView<const std::uint8_t> image,
                             std::vector<OrbKeypoint>& keypoints,
                             std::vector<OrbDescriptor>& descriptors) {
  keypoints.clear();
  descriptors.clear();
  if (!init_status_) return init_status_;
  if (image.empty() || image.width != width_ || image.height != height_)
    return Status::invalidArgument("ORB extractor built for another image size");
  // Pyramid, smoothed layers, score caches.
  ImageU8& c0 = layers_[0].image;
  for (int y = 0; y < height_; ++y) std::copy_n(image.row(y), width_, c0.row(y));
  for (int k = 0; k < numLayers(); ++k) {
    if (k > 0) resampleLayer(k);
    smoothLayer(k);
    layers_[static_cast<std::size_t>(k)].score.fill(kUnknownScore);
  }
  score58_.fill(kUnknownScore);
  // FAST 9-16 candidates on every layer, their scores cached.
  candidates_.clear();
  for (int k = 0; k < numLayers(); ++k) {
    Layer& l = layers_[static_cast<std::size_t>(k)];
    scanFast16(l.image.cview(), params_.fast_threshold, kBorderPx, [&](int x, int y, int s) {
      l.score(x, y) = static_cast<std::uint8_t>(s);
      candidates_.push_back({k, x, y, static_cast<float>(s), 0, 0, 0, 0});
    });
  }
  // Non-maximum suppression in position and scale, refinement, bucketing.
  std::size_t kept = 0;
  for (std::size_t i = 0; i < candidates_.size(); ++i) {
    Candidate c = candidates_[i];
    if (!suppressAndRefine(c)) continue;
    const int cx = std::clamp(static_cast<int>(std::floor(c.x0 * params_.grid_cols / width_)), 0,
                              params_.grid_cols - 1);
    const int cy = std::clamp(static_cast<int>(std::floor(c.y0 * params_.grid_rows / height_)), 0,
                              params_.grid_rows - 1);
    c.cell = cy * params_.grid_cols + cx;
    candidates_[kept++] = c;
  }
  candidates_.resize(kept);
  std::sort(candidates_.begin(), candidates_.end(), [](const Candidate& a, const Candidate& b) {
    if (a.cell != b.cell) return a.cell < b.cell;
    if (a.score != b.score) return a.score > b.score;
    if (a.layer != b.layer) return a.layer < b.layer;
    if (a.y != b.y) return a.y < b.y;
    return a.x < b.x;
  });
  // Orientation and descriptor of the strongest max_per_cell of each cell.
  int run = 0;
  for (std::size_t i = 0; i < candidates_.size(); ++i) {
    const Candidate& c = candidates_[i];
    run = (i > 0 && candidates_[i - 1].cell == c.cell) ? run + 1 : 0;
    if (run >= params_.max_per_cell) continue;
    const Layer& l = layers_[static_cast<std::size_t>(c.layer)];
    OrbKeypoint kp;
    kp.x_px = c.x0;
    kp.y_px = c.y0;
    kp.scale = c.scale;
    kp.size_px = static_cast<float>((2 * kPatchRadiusPx + 1) * l.scale);
    kp.angle_rad = orientation(l, c.x, c.y);
    kp.score = c.score;
    kp.layer = c.layer;
    kp.octave = c.layer / 2;
    keypoints.push_back(kp);
    descriptors.push_back(describe(l, c.x, c.y, kp.angle_rad));
  }
  return Status::ok();
}

}  // namespace svslam
