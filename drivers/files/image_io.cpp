#include "drivers/files/image_io.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <span>
#include <vector>

#include "drivers/files/file_bytes.hpp"

namespace svslam::drivers {
namespace {

namespace fs = std::filesystem;

constexpr float kInvalid = std::numeric_limits<float>::infinity();
constexpr std::int64_t kMaxPfmPixels = std::int64_t{1} << 28;

std::string lowerExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

bool isPng(const Bytes& b) {
  static const unsigned char kSig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  return b.size() >= 8 && std::memcmp(b.data(), kSig, 8) == 0;
}

// PNG colour type from the IHDR chunk (0 grey, 2 RGB, 3 palette, 4 grey+alpha, 6 RGBA), or -1.
int pngColorType(const Bytes& b) {
  if (!isPng(b) || b.size() < 26 || std::memcmp(b.data() + 12, "IHDR", 4) != 0) return -1;
  return b[25];
}

// libjpeg only warns about a premature end of data and fills the rest with grey, so a truncated
// JPEG must be caught here: a complete file has an end-of-image marker (FF D9) after its last
// start-of-scan marker (FF DA). Neither can occur inside entropy-coded data (FF is stuffed).
bool jpegLooksTruncated(const Bytes& b) {
  if (b.size() < 2 || b[0] != 0xFF || b[1] != 0xD8) return false;
  std::ptrdiff_t last_sos = -1;
  std::ptrdiff_t last_eoi = -1;
  for (std::size_t i = 0; i + 1 < b.size(); ++i) {
    if (b[i] != 0xFF) continue;
    if (b[i + 1] == 0xDA) last_sos = static_cast<std::ptrdiff_t>(i);
    if (b[i + 1] == 0xD9) last_eoi = static_cast<std::ptrdiff_t>(i);
  }
  return last_eoi < last_sos || last_eoi < 0;
}

// `bytes` is the file's content, already read for sniffing. Decoding goes through cv::imread,
// not cv::imdecode: OpenCV 4.6 decodes some formats (PFM, EXR) from a buffer via a temporary
// file in /tmp that it leaks when decoding fails.
Result<cv::Mat> decode(const Bytes& bytes, int flags, const std::string& path) {
  if (jpegLooksTruncated(bytes)) {
    return Status::corruptData("cannot decode image " + path +
                               ": truncated JPEG (no end-of-image marker after the last scan)");
  }
  cv::Mat m;
  try {
    m = cv::imread(path, flags);
  } catch (const std::exception& e) {
    return Status::corruptData("cannot decode image " + path + ": " + e.what());
  }
  if (m.empty()) {
    return Status::corruptData("cannot decode image " + path +
                               " (not a format OpenCV reads, or truncated or corrupt)");
  }
  return m;
}

ImageU8 toImageU8(const cv::Mat& m) {
  ImageU8 out(m.cols, m.rows);
  for (int y = 0; y < m.rows; ++y) std::memcpy(out.row(y), m.ptr<std::uint8_t>(y), m.cols);
  return out;
}

Status writePngAtomically(const std::string& path, const cv::Mat& m) {
  std::vector<unsigned char> buf;
  try {
    if (!cv::imencode(".png", m, buf)) return Status::ioError("cannot encode PNG for " + path);
  } catch (const std::exception& e) {
    return Status::ioError("cannot encode PNG for " + path + ": " + e.what());
  }
  return writeFileAtomically(path, buf.data(), buf.size());
}

Status checkWriterArgs(const std::string& path, const char* ext,
                       const ImageView<const float>& img) {
  if (lowerExtension(path) != ext) {
    return Status::invalidArgument("cannot write " + path + ": the file name must end in " + ext);
  }
  if (img.empty()) return Status::invalidArgument("cannot write " + path + ": empty image");
  return Status::ok();
}

std::uint32_t byteSwap(std::uint32_t v) {
  return (v >> 24) | ((v >> 8) & 0x0000FF00u) | ((v << 8) & 0x00FF0000u) | (v << 24);
}

// Next white-space separated token of at most 32 characters, starting at pos.
std::string nextToken(std::span<const unsigned char> b, std::size_t& pos) {
  auto space = [](unsigned char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (pos < b.size() && space(b[pos])) ++pos;
  std::string tok;
  while (pos < b.size() && !space(b[pos]) && tok.size() <= 32) tok += static_cast<char>(b[pos++]);
  return tok;
}

bool parsePositiveInt(const std::string& s, int& out) {
  const char* end = s.data() + s.size();
  const auto r = std::from_chars(s.data(), end, out);
  return r.ec == std::errc() && r.ptr == end && out > 0;
}

}  // namespace

Result<ImageU8> loadGrey(const std::string& path) {
  Result<Bytes> bytes = readFileBytes(path, "image");
  if (!bytes.isOk()) return bytes.status();
  // Palette PNGs go straight through IMREAD_GRAYSCALE, which maps indices through the palette;
  // everything else is decoded as stored so that 16-bit data can be refused, not rescaled.
  if (pngColorType(*bytes) == 3) {
    Result<cv::Mat> m = decode(*bytes, cv::IMREAD_GRAYSCALE | cv::IMREAD_IGNORE_ORIENTATION, path);
    if (!m.isOk()) return m.status();
    return toImageU8(*m);
  }
  Result<cv::Mat> m = decode(*bytes, cv::IMREAD_UNCHANGED, path);
  if (!m.isOk()) return m.status();
  const cv::Mat& src = *m;
  if (src.depth() != CV_8U) {
    const bool is16 = src.depth() == CV_16U || src.depth() == CV_16S;
    return Status::invalidArgument(std::string(is16 ? "16-bit" : "non-8-bit") +
                                   " image where 8-bit grey is needed: " + path);
  }
  const int ch = src.channels();
  if (ch < 1 || ch > 4) {
    return Status::invalidArgument("image with " + std::to_string(ch) +
                                   " channels where 8-bit grey is needed: " + path);
  }
  cv::Mat grey;
  if (ch == 1) grey = src;
  if (ch == 2) cv::extractChannel(src, grey, 0);  // grey + alpha
  if (ch >= 3) cv::cvtColor(src, grey, ch == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
  return toImageU8(grey);
}

Result<ImageF32> loadDisparity(const std::string& path, double scale) {
  if (!std::isfinite(scale) || !(scale > 0.0)) {
    return Status::invalidArgument("disparity scale must be finite and > 0, got " +
                                   std::to_string(scale) + " for " + path);
  }
  const std::string ext = lowerExtension(path);
  if (ext == ".pfm") {
    Result<ImageF32> img = readPfm(path);
    if (!img.isOk()) return img;
    ImageF32& d = *img;
    for (int y = 0; y < d.height(); ++y) {
      float* row = d.row(y);
      for (int x = 0; x < d.width(); ++x) {
        if (!std::isfinite(row[x])) row[x] = kInvalid;
      }
    }
    return img;
  }
  if (ext != ".png") {
    return Status::invalidArgument("unknown disparity file type '" + ext +
                                   "' (expected .pfm or .png): " + path);
  }
  Result<Bytes> bytes = readFileBytes(path, "disparity file");
  if (!bytes.isOk()) return bytes.status();
  const int color_type = pngColorType(*bytes);
  if (color_type == 2 || color_type == 6) {
    return Status::invalidArgument("colour PNG where a grey disparity map is needed: " + path);
  }
  Result<cv::Mat> m = decode(*bytes, cv::IMREAD_GRAYSCALE | cv::IMREAD_ANYDEPTH, path);
  if (!m.isOk()) return m.status();
  const cv::Mat& src = *m;
  if (src.channels() != 1 || (src.depth() != CV_8U && src.depth() != CV_16U)) {
    return Status::invalidArgument("disparity PNG must be 8- or 16-bit grey: " + path);
  }
  ImageF32 out(src.cols, src.rows);
  const double inv_scale = 1.0 / scale;
  for (int y = 0; y < src.rows; ++y) {
    float* dst = out.row(y);
    for (int x = 0; x < src.cols; ++x) {
      const int v =
          src.depth() == CV_8U ? src.ptr<std::uint8_t>(y)[x] : src.ptr<std::uint16_t>(y)[x];
      dst[x] = v == 0 ? kInvalid : static_cast<float>(v * inv_scale);
    }
  }
  return out;
}

Result<ImageU8> loadMask(const std::string& path) {
  Result<ImageU8> img = loadGrey(path);
  if (!img.isOk()) return img;
  ImageU8& m = *img;
  for (int y = 0; y < m.height(); ++y) {
    std::uint8_t* row = m.row(y);
    for (int x = 0; x < m.width(); ++x) row[x] = row[x] == 255 ? 255 : 0;
  }
  return img;
}

Result<ImageF32> readPfm(const std::string& path) {
  Result<Bytes> file = readFileBytes(path, "PFM file");
  if (!file.isOk()) return file.status();
  return parsePfm(file->data(), file->size(), path);
}

Result<ImageF32> parsePfm(const unsigned char* data, std::size_t size, const std::string& path) {
  const std::span<const unsigned char> b(data, size);
  auto bad = [&](const std::string& why) {
    return Status::corruptData("bad PFM header in " + path + ": " + why);
  };
  if (b.size() < 2 || b[0] != 'P' || (b[1] != 'f' && b[1] != 'F')) {
    return bad("does not start with \"Pf\"");
  }
  if (b[1] == 'F') {
    return Status::invalidArgument(
        "colour PFM (\"PF\") where a greyscale one (\"Pf\") is needed: " + path);
  }
  std::size_t pos = 2;
  if (pos >= b.size() || !std::isspace(b[pos])) return bad("no white space after \"Pf\"");
  int width = 0;
  int height = 0;
  const std::string w_tok = nextToken(b, pos);
  if (w_tok.empty()) return bad("ends before the width");
  if (!parsePositiveInt(w_tok, width))
    return bad("width '" + w_tok + "' is not a positive integer");
  const std::string h_tok = nextToken(b, pos);
  if (h_tok.empty()) return bad("ends before the height");
  if (!parsePositiveInt(h_tok, height)) {
    return bad("height '" + h_tok + "' is not a positive integer");
  }
  const std::string s_tok = nextToken(b, pos);
  if (s_tok.empty()) return bad("ends before the scale");
  double scale = 0.0;
  const auto r = std::from_chars(s_tok.data(), s_tok.data() + s_tok.size(), scale);
  if (r.ec != std::errc() || r.ptr != s_tok.data() + s_tok.size() || !std::isfinite(scale) ||
      scale == 0.0) {
    return bad("scale '" + s_tok + "' is not a non-zero number (its sign gives the byte order)");
  }
  if (pos >= b.size()) return bad("ends after the scale, no pixel data");
  // Exactly one white-space character separates the header from the pixels ("\r\n" counts as one).
  pos += (b[pos] == '\r' && pos + 1 < b.size() && b[pos + 1] == '\n') ? 2 : 1;
  const std::int64_t pixels = static_cast<std::int64_t>(width) * height;
  if (pixels > kMaxPfmPixels) {
    return bad(w_tok + " x " + h_tok + " pixels is larger than the " +
               std::to_string(kMaxPfmPixels) + " allowed");
  }
  const std::size_t need = static_cast<std::size_t>(pixels) * 4;
  const std::size_t have = b.size() - pos;
  if (have != need) {
    return Status::corruptData("PFM " + path + " (" + w_tok + " x " + h_tok + ") needs " +
                               std::to_string(need) + " bytes of pixels but has " +
                               std::to_string(have) + (have < need ? " (truncated)" : ""));
  }
  const bool file_little = scale < 0.0;
  const bool swap = file_little != (std::endian::native == std::endian::little);
  ImageF32 out(width, height);
  const unsigned char* src = b.data() + pos;
  for (int file_row = 0; file_row < height; ++file_row) {
    float* dst = out.row(height - 1 - file_row);  // PFM rows run bottom to top
    for (int x = 0; x < width; ++x, src += 4) {
      std::uint32_t u = 0;
      std::memcpy(&u, src, 4);
      if (swap) u = byteSwap(u);
      std::memcpy(&dst[x], &u, 4);
    }
  }
  return out;
}

Status writePfm(const std::string& path, ImageView<const float> img) {
  if (Status s = checkWriterArgs(path, ".pfm", img); !s.isOk()) return s;
  const std::string header =
      "Pf\n" + std::to_string(img.width) + " " + std::to_string(img.height) + "\n-1.0\n";
  std::vector<unsigned char> buf(header.size() +
                                 static_cast<std::size_t>(img.width) * img.height * 4);
  std::memcpy(buf.data(), header.data(), header.size());
  unsigned char* dst = buf.data() + header.size();
  const bool swap = std::endian::native != std::endian::little;
  for (int file_row = 0; file_row < img.height; ++file_row) {
    const float* src = img.row(img.height - 1 - file_row);
    for (int x = 0; x < img.width; ++x, dst += 4) {
      std::uint32_t u = 0;
      std::memcpy(&u, &src[x], 4);
      if (swap) u = byteSwap(u);
      std::memcpy(dst, &u, 4);
    }
  }
  return writeFileAtomically(path, buf.data(), buf.size());
}

Status writeDisparityPng16(const std::string& path, ImageView<const float> disp) {
  if (Status s = checkWriterArgs(path, ".png", disp); !s.isOk()) return s;
  cv::Mat m(disp.height, disp.width, CV_16UC1);
  for (int y = 0; y < disp.height; ++y) {
    const float* src = disp.row(y);
    std::uint16_t* dst = m.ptr<std::uint16_t>(y);
    for (int x = 0; x < disp.width; ++x) {
      const float d = src[x];
      if (!std::isfinite(d) || !(d > 0.0f)) {
        dst[x] = 0;
        continue;
      }
      const double v = std::round(static_cast<double>(d) * 256.0);
      dst[x] = static_cast<std::uint16_t>(std::min(v, 65535.0));
    }
  }
  return writePngAtomically(path, m);
}

Status writeColorPng(const std::string& path, ImageView<const float> disp, float max_disp) {
  if (Status s = checkWriterArgs(path, ".png", disp); !s.isOk()) return s;
  if (!std::isfinite(max_disp) || !(max_disp > 0.0f)) {
    return Status::invalidArgument("cannot write " + path +
                                   ": max_disp must be finite and > 0, got " +
                                   std::to_string(max_disp));
  }
  cv::Mat level(disp.height, disp.width, CV_8UC1);
  cv::Mat invalid(disp.height, disp.width, CV_8UC1);
  for (int y = 0; y < disp.height; ++y) {
    const float* src = disp.row(y);
    std::uint8_t* lv = level.ptr<std::uint8_t>(y);
    std::uint8_t* inv = invalid.ptr<std::uint8_t>(y);
    for (int x = 0; x < disp.width; ++x) {
      const float d = src[x];
      const bool ok = std::isfinite(d) && d >= 0.0f;
      inv[x] = ok ? 0 : 255;
      const float t = ok ? std::min(d / max_disp, 1.0f) : 0.0f;
      lv[x] = static_cast<std::uint8_t>(std::lround(t * 255.0f));
    }
  }
  cv::Mat colour;
  cv::applyColorMap(level, colour, cv::COLORMAP_TURBO);
  colour.setTo(cv::Scalar(0, 0, 0), invalid);
  return writePngAtomically(path, colour);
}

}  // namespace svslam::drivers
