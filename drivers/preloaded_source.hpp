#pragma once
// A recorded source read entirely into memory before a run, so that a paced replay measures the
// pipeline rather than the disk or the synthetic renderer. next() copies the stored pair into
// the caller's buffers (no allocation once they have the size).
#include <memory>
#include <vector>

#include "drivers/stereo_source.hpp"

namespace svslam::io {

// Reads up to `max_frames` pairs (0 = all) of `inner` (which must be finite: size() >= 0).
// Error when a frame cannot be read or the source is live.
Result<std::unique_ptr<StereoSource>> preloadSource(std::unique_ptr<StereoSource> inner,
                                                    int max_frames);

}  // namespace svslam::io
