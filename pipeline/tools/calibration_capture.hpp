#pragma once
// Feeding a StereoCalibrator from a live raw stereo capture (svslam calibrate --source).
//
// Every pair the capture delivers is read (so the cameras never fall behind); a pair is offered
// to the calibrator when
//   grab_every > 0: it is the grab_every-th, 2*grab_every-th, ... pair read (non-interactive);
//   grab_every = 0: trigger() returned kGrab since the previous pair (interactive: Enter).
// Collection ends with `pairs` accepted pairs, when trigger() returns kStop (interactive: 'q' or
// end of stdin), when the capture ends, or after max_frames pairs read (0 = no limit).
// A capture or calibrator error ends it with that error.
#include <functional>
#include <opencv2/core.hpp>
#include <string>

#include "core/status.hpp"
#include "drivers/calib/stereo_calibrator.hpp"
#include "drivers/camera/raw_stereo_capture.hpp"

namespace svslam::cli {

struct LiveCollectOptions {
  int grab_every = 0;  // pairs read between grabs; 0 = on trigger
  int pairs = 15;      // accepted pairs wanted, >= 1
  int max_frames = 0;  // pairs read at most; 0 = unlimited
};

enum class Trigger { kNone, kGrab, kStop };

struct LiveCollectStats {
  int frames_read = 0;  // pairs delivered by the capture
  int offered = 0;      // pairs given to the calibrator
};

// check_left/right: a copy of the first accepted pair (raw), for the rectified check image.
// progress(line): one line per offered pair ("pair 3 (frame 30): accepted, 3/15"), may be empty.
Status collectLivePairs(drivers::RawStereoCapture& capture, drivers::StereoCalibrator& calibrator,
                        const LiveCollectOptions& options, const std::function<Trigger()>& trigger,
                        const std::function<void(const std::string&)>& progress,
                        cv::Mat& check_left, cv::Mat& check_right, LiveCollectStats& stats);

}  // namespace svslam::cli
