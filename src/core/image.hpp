#pragma once
// ImageView<T>: a non-owning 2D view with an explicit row stride (in elements, >= width).
// Image<T>: an owning image whose rows start on 64-byte boundaries (stride rounded up).
// Pixel (x, y) is column x (0 = left) of row y (0 = top).
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "core/aligned_buffer.hpp"

namespace svslam {

template <class T>
struct ImageView {
  T* data = nullptr;
  int width = 0;
  int height = 0;
  std::ptrdiff_t stride = 0;  // elements between the starts of consecutive rows

  ImageView() = default;
  ImageView(T* d, int w, int h, std::ptrdiff_t s) : data(d), width(w), height(h), stride(s) {}
  // A view of mutable pixels converts to a view of const pixels.
  template <class U, class = std::enable_if_t<std::is_same_v<const U, T> && !std::is_same_v<U, T>>>
  ImageView(const ImageView<U>& o)  // NOLINT: implicit by design
      : data(o.data), width(o.width), height(o.height), stride(o.stride) {}

  bool empty() const { return data == nullptr || width <= 0 || height <= 0; }
  T* row(int y) const { return data + static_cast<std::ptrdiff_t>(y) * stride; }
  T& operator()(int x, int y) const { return row(y)[x]; }
  // Sub-rectangle [x0, x0 + w) x [y0, y0 + h); precondition: inside this view.
  ImageView sub(int x0, int y0, int w, int h) const {
    return ImageView(row(y0) + x0, w, h, stride);
  }
};

template <class T>
class Image {
 public:
  Image() = default;
  Image(int width, int height) { resize(width, height); }
  Image(Image&&) noexcept = default;
  Image& operator=(Image&&) noexcept = default;

  // Reallocates only when the size changes; contents are zeroed on reallocation.
  void resize(int width, int height) {
    if (width == width_ && height == height_) return;
    const std::ptrdiff_t per_line = static_cast<std::ptrdiff_t>(kAlignBytes / sizeof(T));
    stride_ = (width + per_line - 1) / per_line * per_line;
    width_ = width;
    height_ = height;
    buf_.resize(static_cast<std::size_t>(stride_) * static_cast<std::size_t>(height));
  }
  int width() const { return width_; }
  int height() const { return height_; }
  std::ptrdiff_t stride() const { return stride_; }
  bool empty() const { return width_ <= 0 || height_ <= 0; }
  T* row(int y) { return buf_.data() + static_cast<std::ptrdiff_t>(y) * stride_; }
  const T* row(int y) const { return buf_.data() + static_cast<std::ptrdiff_t>(y) * stride_; }
  T& operator()(int x, int y) { return row(y)[x]; }
  const T& operator()(int x, int y) const { return row(y)[x]; }
  ImageView<T> view() { return {buf_.data(), width_, height_, stride_}; }
  ImageView<const T> view() const { return {buf_.data(), width_, height_, stride_}; }
  ImageView<const T> cview() const { return view(); }
  void fill(const T& v) {
    for (int y = 0; y < height_; ++y)
      for (int x = 0; x < width_; ++x) row(y)[x] = v;
  }

 private:
  AlignedBuffer<T> buf_;
  int width_ = 0;
  int height_ = 0;
  std::ptrdiff_t stride_ = 0;
};

using ImageU8 = Image<std::uint8_t>;
using ImageF32 = Image<float>;

}  // namespace svslam
