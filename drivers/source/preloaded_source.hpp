#pragma once
// A recorded source read entirely into memory before a run, so that a paced replay measures the
// pipeline rather than the disk or the synthetic renderer. next() copies the stored pair into
// the caller's buffers (no allocation once they have the size).
#include <memory>
#include <vector>

#include "drivers/source/stereo_source.hpp"

namespace svslam::drivers {

class PreloadedSource final : public StereoSource {
 public:
  const StereoCalibration& calibration() const override { return inner_->calibration(); }
  int size() const override { return static_cast<int>(frames_.size()) * loops_; }
  Result<bool> next(StereoFrame& out) override;
  int skippedFrames() const override { return inner_->skippedFrames(); }
  std::string skippedFramesDetail() const override { return inner_->skippedFramesDetail(); }
  std::vector<std::pair<std::string, std::int64_t>> counters() const override {
    return inner_->counters();
  }
  bool groundTruth(int index, Eigen::Isometry3d& T_first_cam) const override {
    return inner_->groundTruth(index, T_first_cam);
  }
  bool gravityInFirstCamera(Eigen::Vector3d& g) const override {
    return inner_->gravityInFirstCamera(g);
  }
  bool groundTruthDem(const Eigen::Matrix3d& R_map_world, int frames,
                      map::DemRaster& raster) const override {
    return inner_->groundTruthDem(R_map_world, frames, raster);
  }
  // Starts again from the first frame (a benchmark replays the same frames twice).
  void rewind() {
    next_ = 0;
    loop_ = 0;
  }
  // Replays the stored frames `loops` times (1..1e6) in one stream: replay k continues the frame
  // index (index + k n, n stored frames) and the clock (t_ns + k period, period = the stored
  // stamps' span plus their last interval), so a flight whose frame n would be its frame 0 (a
  // synthetic flight with loop_frames = n) runs on without a jump. Needs n >= 2 for loops > 1.
  // Ground truth is the inner source's: none for the replays after the first.
  Status setLoops(int loops);

 private:
  friend Result<std::unique_ptr<PreloadedSource>> preload(std::unique_ptr<StereoSource>, int,
                                                          const StopQuery&);
  std::unique_ptr<StereoSource> inner_;
  std::vector<StereoFrame> frames_;
  std::size_t next_ = 0;
  int loops_ = 1, loop_ = 0;
  TimeNs period_ns_ = 0;
};

// Reads up to `max_frames` pairs (0 = all) of `inner` (which must be finite: size() >= 0).
// Error when a frame cannot be read or the source is live. `stop` (when set) is polled before
// each frame: true ends the reading early, keeping the frames read so far.
Result<std::unique_ptr<PreloadedSource>> preload(std::unique_ptr<StereoSource> inner,
                                                 int max_frames, const StopQuery& stop = {});
// The same, as a plain StereoSource.
Result<std::unique_ptr<StereoSource>> preloadSource(std::unique_ptr<StereoSource> inner,
                                                    int max_frames, const StopQuery& stop = {});

}  // namespace svslam::drivers
