#include "drivers/source/preloaded_source.hpp"

#include <climits>
#include <cstring>
#include <string>

namespace svslam::drivers {
namespace {

void copyImage(const ImageU8& from, ImageU8& to) {
  to.resize(from.width(), from.height());
  for (int y = 0; y < from.height(); ++y)
    std::memcpy(to.row(y), from.row(y), static_cast<std::size_t>(from.width()));
}

}  // namespace

Status PreloadedSource::setLoops(int loops) {
  if (loops < 1 || loops > 1000000)
    return Status::invalidArgument("replay loops must be in [1, 1000000], got " +
                                   std::to_string(loops));
  if (loops > 1 && frames_.size() < 2)
    return Status::invalidArgument("replaying a sequence in a loop needs at least 2 frames, got " +
                                   std::to_string(frames_.size()));
  if (static_cast<long long>(loops) * static_cast<long long>(frames_.size()) > INT_MAX)
    return Status::invalidArgument("replay loops: " + std::to_string(loops) + " replays of " +
                                   std::to_string(frames_.size()) + " frames exceed 2^31 frames");
  if (loops > 1) {
    const std::size_t n = frames_.size();
    const TimeNs last_dt = frames_[n - 1].t_ns - frames_[n - 2].t_ns;
    period_ns_ = frames_[n - 1].t_ns - frames_[0].t_ns + last_dt;
    if (last_dt <= 0 || period_ns_ <= 0)
      return Status::invalidArgument("replaying a sequence in a loop needs increasing stamps");
  }
  loops_ = loops;
  return Status::ok();
}

Result<bool> PreloadedSource::next(StereoFrame& out) {
  if (next_ >= frames_.size()) {
    if (loop_ + 1 >= loops_) return false;
    ++loop_;
    next_ = 0;
  }
  const StereoFrame& f = frames_[next_++];
  out.index = f.index + loop_ * static_cast<int>(frames_.size());
  out.t_ns = f.t_ns + static_cast<TimeNs>(loop_) * period_ns_;
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
