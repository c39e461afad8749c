#include "drivers/preloaded_source.hpp"

#include <cstring>

namespace svslam::io {
namespace {

void copyImage(const ImageU8& from, ImageU8& to) {
  to.resize(from.width(), from.height());
  for (int y = 0; y < from.height(); ++y)
    std::memcpy(to.row(y), from.row(y), static_cast<std::size_t>(from.width()));
}

class PreloadedSource final : public StereoSource {
 public:
  explicit PreloadedSource(std::unique_ptr<StereoSource> inner) : inner_(std::move(inner)) {}
  Status load(int max_frames) {
    for (;;) {
      if (max_frames > 0 && static_cast<int>(frames_.size()) >= max_frames) break;
      StereoFrame f;
      auto more = inner_->next(f);
      if (!more) return more.status();
      if (!*more) break;
      frames_.push_back(std::move(f));
    }
    return Status::ok();
  }
  const StereoCalibration& calibration() const override { return inner_->calibration(); }
  int size() const override { return static_cast<int>(frames_.size()); }
  Result<bool> next(StereoFrame& out) override {
    if (next_ >= frames_.size()) return false;
    const StereoFrame& f = frames_[next_++];
    out.index = f.index;
    out.t_ns = f.t_ns;
    copyImage(f.left, out.left);
    copyImage(f.right, out.right);
    return true;
  }
  bool groundTruth(int index, Eigen::Isometry3d& T_first_cam) const override {
    return inner_->groundTruth(index, T_first_cam);
  }

 private:
  std::unique_ptr<StereoSource> inner_;
  std::vector<StereoFrame> frames_;
  std::size_t next_ = 0;
};

}  // namespace

Result<std::unique_ptr<StereoSource>> preloadSource(std::unique_ptr<StereoSource> inner,
                                                    int max_frames) {
  if (!inner) return Status::invalidArgument("preload: no source");
  if (inner->size() < 0)
    return Status::invalidArgument("preload: a live source cannot be read in advance");
  auto p = std::make_unique<PreloadedSource>(std::move(inner));
  if (Status s = p->load(max_frames); !s) return s;
  return std::unique_ptr<StereoSource>(std::move(p));
}

}  // namespace svslam::io
