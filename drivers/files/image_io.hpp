#pragma once
// Image and disparity files: decoding through OpenCV's codecs, PFM by hand.
//
// Conventions:
//  - Pixel (x, y) is column x of row y, row 0 at the top, in every returned image.
//  - Disparity maps are float pixels, d = x_left - x_right; an invalid (unknown) disparity is
//    +inf. NaN or -inf never come out of the loaders.
//  - Errors are values naming the file: notFound (no such file), corruptData (the file exists
//    but cannot be decoded, e.g. garbage bytes, truncated PNG or JPEG, garbled PFM header; the
//    reason is in the message), invalidArgument (bad parameter, empty file, unknown extension,
//    a 16-bit or otherwise unsuitable image), ioError (a read or write failed).
//  - Writers write `path + ".tmp"` and rename it to `path`, so a reader never sees half a
//    file; on failure they return ioError naming the path and leave no ".tmp" behind.
//  - File extensions are matched case-insensitively.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/image.hpp"
#include "core/status.hpp"

namespace svslam::drivers {

// 8-bit grey image from any format OpenCV decodes (PNG, JPEG, PGM, BMP, TIFF, ...).
// Colour images become grey (OpenCV's 0.299 R + 0.587 G + 0.114 B); palette PNGs are read
// through their palette. 16-bit (or float) images are refused with invalidArgument ("16-bit
// image where 8-bit grey is needed") rather than silently rescaled. EXIF orientation is
// ignored: pixels come as stored, which is what rectified stereo needs.
Result<ImageU8> loadGrey(const std::string& path);

// Disparity map in pixels, by extension:
//  .pfm: floats as stored (greyscale "Pf" only; see readPfm); non-finite -> +inf.
//  .png: 8- or 16-bit grey (palette PNGs through the palette), d = value / scale, value 0 -> +inf
//        (unknown). KITTI: scale 256; Middlebury v2: scale from info.txt (e.g. tsukuba 16).
// scale must be finite and > 0 (checked for every extension), else invalidArgument.
Result<ImageF32> loadDisparity(const std::string& path, double scale);

// Evaluation mask, 8-bit, returned as 0 (skip) or 255 (evaluate). Follows the Middlebury
// convention: only white (255) pixels are evaluated. This matters for Middlebury's disc.png,
// where 255 = near a depth discontinuity, 128 = non-occluded elsewhere, 0 = occluded; nonocc.png
// and all.png hold only 0 and 255.
Result<ImageU8> loadMask(const std::string& path);

// Greyscale PFM ("Pf"). Header: "Pf", width, height, scale, each separated by white space, then a
// single white space character (usually '\n') and width*height 4-byte floats, rows stored from
// the BOTTOM of the image to the top. Negative scale = little-endian, positive = big-endian;
// the magnitude is not applied. Values are returned exactly as stored (NaN / inf included).
// Colour PFM ("PF") -> invalidArgument; truncated or garbled header or pixel data -> corruptData
// with the reason.
Result<ImageF32> readPfm(const std::string& path);
// The same from the file's bytes (readPfm reads the file, then calls this); `path` names the
// file in errors.
Result<ImageF32> parsePfm(const unsigned char* data, std::size_t size, const std::string& path);

// Writes "Pf\n<W> <H>\n-1.0\n" then little-endian floats, bottom row first. The path must end in
// ".pfm"; img must be non-empty.
Status writePfm(const std::string& path, ImageView<const float> img);

// KITTI disparity PNG: uint16 = round(d * 256) saturated at 65535; 0 (= no disparity) where d is
// non-finite or <= 0, and for 0 < d < 1/512, which rounds to 0. The path must end in ".png".
Status writeDisparityPng16(const std::string& path, ImageView<const float> disp);

// A colour picture for people: the TURBO colour map of clamp(d / max_disp, 0, 1), near (large
// disparity) = warm/red, far = cold/blue; invalid pixels (non-finite or negative d) black.
// max_disp (px) must be finite and > 0. The path must end in ".png".
Status writeColorPng(const std::string& path, ImageView<const float> disp, float max_disp);

}  // namespace svslam::drivers
