// Raw (unrectified) live stereo pairs (see raw_stereo_capture.hpp).
#include "drivers/camera/raw_stereo_capture.hpp"

#include <vector>

#include "drivers/camera/libcamera_source.hpp"
#include "drivers/camera/pixel_formats.hpp"
#include "drivers/camera/v4l2_capture.hpp"
#include "drivers/camera/v4l2_source.hpp"

namespace svslam::drivers {
namespace {

class V4l2RawCapture final : public RawStereoCapture {
 public:
  V4l2RawCapture(std::vector<std::unique_ptr<V4l2Capture>> caps, TimeNs sync_ns)
      : caps_(std::move(caps)), pairer_(sync_ns) {}
  Result<bool> next(ImageU8& left, ImageU8& right, TimeNs& t_ns) override {
    std::uint32_t seq = 0;
    if (caps_.size() == 1) {
      auto r = caps_[0]->grab(full_, t_ns, seq);
      if (!r || !*r) return r;
      if (Status s = splitSideBySide(full_, left, right); !s) return s;
      return true;
    }
    return pairer_.next(
        [this, &seq](int c, ImageU8& img, TimeNs& t) {
          return caps_[static_cast<std::size_t>(c)]->grab(img, t, seq);
        },
        left, right, t_ns);
  }

 private:
  std::vector<std::unique_ptr<V4l2Capture>> caps_;
  TimestampPairer pairer_;
  ImageU8 full_;
};

}  // namespace

Result<std::unique_ptr<RawStereoCapture>> openRawStereoCapture(const std::string& spec,
                                                               V4l2Device& device) {
  if (spec.rfind("v4l2:", 0) == 0) {
    auto setup = parseV4l2Setup(spec.substr(5));
    if (!setup) return setup.status();
    auto caps = openV4l2Captures(*setup, device);
    if (!caps) return caps.status();
    return std::unique_ptr<RawStereoCapture>(
        std::make_unique<V4l2RawCapture>(std::move(caps).value(), setup->sync_tolerance_ns));
  }
  if (spec.rfind("libcamera:", 0) == 0) {
#ifdef SVSLAM_HAVE_LIBCAMERA
    return openLibcameraRawCapture(spec.substr(10));
#else
    return Status::failedPrecondition("libcamera support not built (libcamera-dev not found)");
#endif
  }
  return Status::invalidArgument("live calibration needs a v4l2: or libcamera: source, got '" +
                                 spec + "'");
}

Result<std::unique_ptr<RawStereoCapture>> openRawStereoCapture(const std::string& spec) {
  return openRawStereoCapture(spec, systemV4l2Device());
}

}  // namespace svslam::drivers
