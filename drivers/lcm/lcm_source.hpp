#pragma once
// The `lcm:` stereo source: rectified grey pairs received as svslam_lcm::stereo_image_t.
//
//   lcm:CHANNEL[?timeout_s=S&queue=N&url=URL]
//     CHANNEL    channel of the stereo_image_t messages
//     timeout_s  longest wait for a frame, seconds (default 10): open() fails when no valid
//                image arrives in time; next() ends the sequence (returns false)
//     queue      frames buffered between the receiver thread and next() (default 4); when
//                full the oldest is dropped (newest kept) and counted
//     url        LCM URL (default udpm://239.255.76.67:7667?ttl=0); must come last, it takes
//                the rest of the spec verbatim (URLs carry their own '?' and '&')
//
// The calibration (f, cx, cy, baseline, size) comes from the first valid message; later
// messages with another size or calibration, and malformed ones, are skipped and counted.
// A receiver thread (started by open, stopped by the destructor) handles LCM traffic.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "drivers/lcm/lcm_transport.hpp"
#include "drivers/source/stereo_source.hpp"

namespace svslam::drivers {

struct LcmSourceParams {
  std::string channel;                // validateChannelName
  std::string url = LcmParams{}.url;  // LCM URL
  double timeout_s = 10.0;            // (0, 86400], seconds
  int queue_capacity = 4;             // [1, 256] frames

  Status validate() const;
};

// Parses the text after "lcm:" (grammar above).
Result<LcmSourceParams> parseLcmSourceSpec(const std::string& spec_after_prefix);

class LcmStereoSource : public StereoSource {
 public:
  ~LcmStereoSource() override;
  const StereoCalibration& calibration() const override { return calib_; }
  int size() const override { return -1; }
  Result<bool> next(StereoFrame& out) override;

  // Messages that could not be decoded or failed validateStereoImage.
  std::int64_t malformedCount() const { return malformed_.load(); }
  // Valid messages whose size or calibration differs from the first one.
  std::int64_t mismatchCount() const { return mismatched_.load(); }
  // Frames dropped because the queue was full (the consumer was too slow).
  std::int64_t droppedCount() const { return dropped_.load(); }

 private:
  friend Result<std::unique_ptr<StereoSource>> openLcmSource(const LcmSourceParams&, LcmLink&,
                                                             const StopQuery&);
  friend Result<std::unique_ptr<StereoSource>> openLcmSource(const std::string&, const StopQuery&);
  explicit LcmStereoSource(LcmSourceParams params) : params_(std::move(params)) {}
  // Subscribes, starts the receiver, waits for the first frame (polling `stop` every 50 ms).
  Status start(LcmLink& link, const StopQuery& stop);
  void onImage(const std::uint8_t* data, std::size_t size);
  void receiveLoop();

  LcmSourceParams params_;
  std::unique_ptr<LcmLink> owned_link_;  // when opened from a URL
  LcmLink* link_ = nullptr;
  int sub_id_ = 0;
  StereoCalibration calib_;
  int index_ = 0;

  std::mutex mu_;  // guards queue_, have_calib_, ended_, end_status_
  std::condition_variable cv_;
  std::deque<svslam_lcm::stereo_image_t> queue_;
  bool have_calib_ = false;
  bool ended_ = false;  // receiver stopped (end of a replayed log, LCM failure)
  Status end_status_;
  std::atomic<bool> stop_{false};
  std::thread rx_;

  std::atomic<std::int64_t> malformed_{0}, mismatched_{0}, dropped_{0};
};

// "CHANNEL[?timeout_s=S&queue=N&url=URL]": opens its own LcmLink on the URL. While it waits for
// the first frame, `stop` (when set) is polled every 50 ms; true ends the wait with an error
// saying so.
Result<std::unique_ptr<StereoSource>> openLcmSource(const std::string& spec_after_prefix,
                                                    const StopQuery& stop = {});
// Receives on an existing link (e.g. memq:// shared with a publisher in this process); the
// link must outlive the source. The URL of params is ignored.
Result<std::unique_ptr<StereoSource>> openLcmSource(const LcmSourceParams& params, LcmLink& link,
                                                    const StopQuery& stop = {});

}  // namespace svslam::drivers
