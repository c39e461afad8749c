#pragma once
// Conversion of one captured camera buffer to 8-bit grey, and splitting of side-by-side frames.
//
// Formats (V4L2 fourcc in brackets):
//   GREY  ('GREY') 8 bits per pixel, rows `bytes_per_line` bytes apart (>= width).
//   YUYV  ('YUYV') 4:2:2 packed Y0 U Y1 V; grey is the luma Y. Rows `bytes_per_line` bytes
//         apart (>= 2 width); width must be even.
//   MJPEG ('MJPG') one JPEG per buffer, decoded as grey by OpenCV (libjpeg); the buffer must
//         start with SOI (FF D8) and hold EOI (FF D9) before any zero padding, so a truncated
//         frame is an error rather than a half-grey image. The decoded size must match.
// Every error is a Status value (corruptData for bad buffer contents, invalidArgument for bad
// parameters) whose message names the format and what was wrong; nothing throws.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/image.hpp"
#include "core/status.hpp"

namespace svslam::drivers {

enum class PixelFormat { kGrey, kYuyv, kMjpeg };

// "GREY", "YUYV" or "MJPEG" (case-sensitive; "MJPG" accepted too).
Result<PixelFormat> parsePixelFormat(const std::string& name);
const char* pixelFormatName(PixelFormat format);
// The V4L2 fourcc (V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_MJPEG).
std::uint32_t pixelFormatFourcc(PixelFormat format);
// Inverse of pixelFormatFourcc; an error naming the fourcc for anything else.
Result<PixelFormat> pixelFormatFromFourcc(std::uint32_t fourcc);
// Four printable characters of a fourcc, e.g. "YUYV".
std::string fourccToString(std::uint32_t fourcc);
// Minimum bytes per line of an uncompressed format (0 for MJPEG).
std::size_t minBytesPerLine(PixelFormat format, int width);

// Converts `bytes_used` bytes at `data` holding a width x height frame into `grey_out`
// (resized to width x height). bytes_per_line = 0 means tightly packed.
Status convertToGrey(PixelFormat format, const std::uint8_t* data, std::size_t bytes_used,
                     int width, int height, std::size_t bytes_per_line, ImageU8& grey_out);

// Splits a side-by-side frame (left view in columns [0, W/2), right in [W/2, W)); the width
// must be even and > 0.
Status splitSideBySide(const ImageU8& full, ImageU8& left_out, ImageU8& right_out);

}  // namespace svslam::drivers
