// Camera buffer -> grey conversion (see pixel_formats.hpp).
#include "drivers/camera/pixel_formats.hpp"

#include <linux/videodev2.h>

#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <vector>

namespace svslam::drivers {

Result<PixelFormat> parsePixelFormat(const std::string& name) {
  if (name == "GREY") return PixelFormat::kGrey;
  if (name == "YUYV") return PixelFormat::kYuyv;
  if (name == "MJPEG" || name == "MJPG") return PixelFormat::kMjpeg;
  return Status::invalidArgument("unknown pixel format '" + name + "' (use GREY, YUYV or MJPEG)");
}

const char* pixelFormatName(PixelFormat format) {
  switch (format) {
    case PixelFormat::kGrey:
      return "GREY";
    case PixelFormat::kYuyv:
      return "YUYV";
    case PixelFormat::kMjpeg:
      return "MJPEG";
  }
  return "?";
}

std::uint32_t pixelFormatFourcc(PixelFormat format) {
  switch (format) {
    case PixelFormat::kGrey:
      return V4L2_PIX_FMT_GREY;
    case PixelFormat::kYuyv:
      return V4L2_PIX_FMT_YUYV;
    case PixelFormat::kMjpeg:
      return V4L2_PIX_FMT_MJPEG;
  }
  return 0;
}

Result<PixelFormat> pixelFormatFromFourcc(std::uint32_t fourcc) {
  for (PixelFormat f : {PixelFormat::kGrey, PixelFormat::kYuyv, PixelFormat::kMjpeg})
    if (pixelFormatFourcc(f) == fourcc) return f;
  return Status::invalidArgument("unsupported pixel format '" + fourccToString(fourcc) + "'");
}

std::string fourccToString(std::uint32_t fourcc) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xFF);
    s += (c >= 32 && c < 127) ? c : '?';
  }
  return s;
}

std::size_t minBytesPerLine(PixelFormat format, int width) {
  const auto w = static_cast<std::size_t>(width);
  switch (format) {
    case PixelFormat::kGrey:
      return w;
    case PixelFormat::kYuyv:
      return 2 * w;
    case PixelFormat::kMjpeg:
      return 0;
  }
  return 0;
}

namespace {

Status decodeMjpeg(const std::uint8_t* data, std::size_t bytes_used, int width, int height,
                   ImageU8& grey_out) {
  if (bytes_used < 4 || data[0] != 0xFF || data[1] != 0xD8)
    return Status::corruptData("MJPEG buffer of " + std::to_string(bytes_used) +
                               " bytes does not start with a JPEG SOI marker");
  std::size_t end = bytes_used;  // UVC cameras may pad the JPEG with zeros
  while (end > 2 && data[end - 1] == 0) --end;
  if (data[end - 2] != 0xFF || data[end - 1] != 0xD9)
    return Status::corruptData("MJPEG buffer of " + std::to_string(bytes_used) +
                               " bytes is truncated (no JPEG EOI marker)");
  cv::Mat decoded;
  try {
    const cv::Mat raw(1, static_cast<int>(end), CV_8U, const_cast<std::uint8_t*>(data));
    decoded = cv::imdecode(raw, cv::IMREAD_GRAYSCALE);
  } catch (const cv::Exception& e) {
    return Status::corruptData(std::string("MJPEG buffer cannot be decoded: ") + e.what());
  }
  if (decoded.empty() || decoded.type() != CV_8U)
    return Status::corruptData("MJPEG buffer of " + std::to_string(bytes_used) +
                               " bytes cannot be decoded as JPEG");
  if (decoded.cols != width || decoded.rows != height)
    return Status::corruptData("MJPEG frame decodes to " + std::to_string(decoded.cols) + "x" +
                               std::to_string(decoded.rows) + ", expected " +
                               std::to_string(width) + "x" + std::to_string(height));
  grey_out.resize(width, height);
  for (int y = 0; y < height; ++y)
    std::memcpy(grey_out.row(y), decoded.ptr<std::uint8_t>(y), static_cast<std::size_t>(width));
  return Status::ok();
}

}  // namespace

Status convertToGrey(PixelFormat format, const std::uint8_t* data, std::size_t bytes_used,
                     int width, int height, std::size_t bytes_per_line, ImageU8& grey_out) {
  if (width <= 0 || height <= 0)
    return Status::invalidArgument("convertToGrey: image size must be > 0");
  if (data == nullptr) return Status::invalidArgument("convertToGrey: null buffer");
  if (format == PixelFormat::kMjpeg) return decodeMjpeg(data, bytes_used, width, height, grey_out);
  if (format == PixelFormat::kYuyv && width % 2 != 0)
    return Status::invalidArgument("YUYV frame width must be even, got " + std::to_string(width));
  const std::size_t min_line = minBytesPerLine(format, width);
  if (bytes_per_line == 0) bytes_per_line = min_line;
  if (bytes_per_line < min_line)
    return Status::invalidArgument(
        std::string(pixelFormatName(format)) + " bytes per line " + std::to_string(bytes_per_line) +
        " < " + std::to_string(min_line) + " for width " + std::to_string(width));
  // The last row need only hold its pixels, not the full stride.
  const std::size_t needed = bytes_per_line * static_cast<std::size_t>(height - 1) + min_line;
  if (bytes_used < needed)
    return Status::corruptData(std::string(pixelFormatName(format)) + " buffer truncated: " +
                               std::to_string(bytes_used) + " bytes, " + std::to_string(width) +
                               "x" + std::to_string(height) + " needs " + std::to_string(needed));
  grey_out.resize(width, height);
  for (int y = 0; y < height; ++y) {
    const std::uint8_t* src = data + bytes_per_line * static_cast<std::size_t>(y);
    std::uint8_t* dst = grey_out.row(y);
    if (format == PixelFormat::kGrey) {
      std::memcpy(dst, src, static_cast<std::size_t>(width));
    } else {
      for (int x = 0; x < width; ++x) dst[x] = src[2 * x];
    }
  }
  return Status::ok();
}

Status splitSideBySide(const ImageU8& full, ImageU8& left_out, ImageU8& right_out) {
  if (full.empty() || full.width() % 2 != 0)
    return Status::invalidArgument("side-by-side frame width must be even and > 0, got " +
                                   std::to_string(full.width()));
  const int half = full.width() / 2;
  left_out.resize(half, full.height());
  right_out.resize(half, full.height());
  for (int y = 0; y < full.height(); ++y) {
    std::memcpy(left_out.row(y), full.row(y), static_cast<std::size_t>(half));
    std::memcpy(right_out.row(y), full.row(y) + half, static_cast<std::size_t>(half));
  }
  return Status::ok();
}

}  // namespace svslam::drivers
