#include "drivers/source/preloaded_source.hpp"

#include <cstring>

namespace svslam::drivers {
namespace {

void copyImage(const ImageU8& from, ImageU8& to) {
  to.resize(from.width(), from.height());
  for (int y = 0; y < from.height(); ++y)
    std::memcpy(to.row(y), from.row(y), static_cast<std::size_t>(from.width()));
}

}  // namespace

Result<bool> PreloadedSource::next(StereoFrame& out) {
  if (next_ >= frames_.size()) return false;
  const StereoFrame& f = frames_[next_++];
  out.index = f.index;
  out.t_ns = f.t_ns;
  copyImage(f.left, out.left);
  copyImage(f.right, out.right);
  return true;
}

Result<std::unique_ptr<PreloadedSource>> preload(std::unique_ptr<StereoSource> inner,
                                                 int max_frames, const StopQuery& stop) {
  if (!inner) return Status::invalidArgument("preload: no source");
  if (inner->size() < 0)
    return Status::invalidArgument("preload: a live source cannot be read in advance");
  auto p = std::unique_ptr<PreloadedSource>(new PreloadedSource());
  p->inner_ = std::move(inner);
  for (;;) {
    if (max_frames > 0 && static_cast<int>(p->frames_.size()) >= max_frames) break;
    if (stop && stop()) break;
    StereoFrame f;
    auto more = p->inner_->next(f);
    if (!more) return more.status();
    if (!*more) break;
    p->frames_.push_back(std::move(f));
  }
  return p;
}

Result<std::unique_ptr<StereoSource>> preloadSource(std::unique_ptr<StereoSource> inner,
                                                    int max_frames, const StopQuery& stop) {
  auto p = preload(std::move(inner), max_frames, stop);
  if (!p) return p.status();
  return std::unique_ptr<StereoSource>(std::move(*p));
}

}  // namespace svslam::drivers
