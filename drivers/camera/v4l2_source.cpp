// v4l2: stereo source, camera spec parsing, calibration + rectification, timestamp pairing
// (see v4l2_source.hpp).
#include "drivers/camera/v4l2_source.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "drivers/files/opencv_view.hpp"
#include "drivers/camera/pixel_formats.hpp"
#include "drivers/files/stereo_calibration_file.hpp"

namespace svslam::drivers {
namespace {

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t p = s.find(sep, start);
    out.push_back(s.substr(start, p == std::string::npos ? std::string::npos : p - start));
    if (p == std::string::npos) return out;
    start = p + 1;
  }
}

Result<double> number(const CameraSpec& spec, const std::string& key, double fallback,
                      const std::string& scheme) {
  auto it = spec.options.find(key);
  if (it == spec.options.end()) return fallback;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  if (it->second.empty() || *end != '\0' || !std::isfinite(v))
    return Status::invalidArgument(scheme + ": option " + key + "='" + it->second +
                                   "' is not a number");
  return v;
}

Result<int> integer(const CameraSpec& spec, const std::string& key, int fallback,
                    const std::string& scheme) {
  auto v = number(spec, key, fallback, scheme);
  if (!v) return v.status();
  if (*v != std::floor(*v) || std::abs(*v) > 1e9)
    return Status::invalidArgument(scheme + ": option " + key + " must be an integer");
  return static_cast<int>(*v);
}

}  // namespace

Result<CameraSpec> parseCameraSpec(const std::string& spec, const std::string& scheme,
                                   const std::set<std::string>& allowed) {
  CameraSpec out;
  const std::size_t q = spec.find('?');
  for (const std::string& d : split(spec.substr(0, q), ','))
    if (!d.empty()) out.devices.push_back(d);
  if (out.devices.empty())
    return Status::invalidArgument(scheme + ": no camera given in '" + spec + "'");
  if (q == std::string::npos) return out;
  for (const std::string& kv : split(spec.substr(q + 1), '&')) {
    if (kv.empty()) continue;
    const std::size_t eq = kv.find('=');
    const std::string key = kv.substr(0, eq);
    if (!allowed.count(key))
      return Status::invalidArgument(scheme + ": unknown option '" + key + "'");
    if (eq == std::string::npos)
      return Status::invalidArgument(scheme + ": option '" + key + "' needs a value");
    out.options[key] = kv.substr(eq + 1);
  }
  return out;
}

Status StereoRectification::apply(const ImageU8& raw_left, const ImageU8& raw_right,
                                  StereoFrame& out) const {
  for (const ImageU8* raw : {&raw_left, &raw_right})
    if (raw->width() != calib.width || raw->height() != calib.height)
      return Status::invalidArgument("rectification: raw view is " + std::to_string(raw->width()) +
                                     "x" + std::to_string(raw->height()) + ", calibration is for " +
                                     std::to_string(calib.width) + "x" +
                                     std::to_string(calib.height));
  out.left.resize(calib.width, calib.height);
  out.right.resize(calib.width, calib.height);
  cv::Mat l = asMat(out.left), r = asMat(out.right);
  cv::remap(asMat(raw_left), l, map_left_x, map_left_y, cv::INTER_LINEAR);
  cv::remap(asMat(raw_right), r, map_right_x, map_right_y, cv::INTER_LINEAR);
  return Status::ok();
}

Status StereoRectification::applyLeft(const ImageU8& raw_left, StereoFrame& out) const {
  if (raw_left.width() != calib.width || raw_left.height() != calib.height)
    return Status::invalidArgument("rectification: raw view is " +
                                   std::to_string(raw_left.width()) + "x" +
                                   std::to_string(raw_left.height()) +
                                   ", calibration is for " + std::to_string(calib.width) + "x" +
                                   std::to_string(calib.height));
  out.left.resize(calib.width, calib.height);
  out.right.resize(0, 0);
  cv::Mat l = asMat(out.left);
  cv::remap(asMat(raw_left), l, map_left_x, map_left_y, cv::INTER_LINEAR);
  return Status::ok();
}

Result<StereoRectification> loadStereoRectification(const std::string& file, int width,
                                                    int height) {
  auto c = readStereoCalibrationFile(file);
  if (!c) return c.status();
  if (c->width != width || c->height != height)
    return Status::invalidArgument(file + ": calibrated for " + std::to_string(c->width) + "x" +
                                   std::to_string(c->height) + " but the capture is " +
                                   std::to_string(width) + "x" + std::to_string(height));
  try {
    const cv::Size sz(width, height);
    cv::Mat R1, R2, P1, P2, Q;
    cv::stereoRectify(c->K1, c->D1, c->K2, c->D2, sz, c->R, c->T, R1, R2, P1, P2, Q,
                      cv::CALIB_ZERO_DISPARITY, 0.0);
    StereoRectification rect;
    cv::initUndistortRectifyMap(c->K1, c->D1, R1, P1, sz, CV_16SC2, rect.map_left_x,
                                rect.map_left_y);
    cv::initUndistortRectifyMap(c->K2, c->D2, R2, P2, sz, CV_16SC2, rect.map_right_x,
                                rect.map_right_y);
    rect.calib.f_px = P1.at<double>(0, 0);
    rect.calib.cx_px = P1.at<double>(0, 2);
    rect.calib.cy_px = P1.at<double>(1, 2);
    rect.calib.baseline_m = -P2.at<double>(0, 3) / P2.at<double>(0, 0);
    rect.calib.width = width;
    rect.calib.height = height;
    if (Status s = rect.calib.validate(); !s)
      return Status(s.code(),
                    file + ": rectified " + s.message() + " (is T in metres, right camera at +x?)");
    return rect;
  } catch (const cv::Exception& e) {
    return Status::corruptData(file + ": cannot read calibration: " + e.what());
  }
}

Result<bool> TimestampPairer::next(const GrabFn& grab, ImageU8& left, ImageU8& right,
                                   TimeNs& t_ns) {
  int drops_in_row = 0;
  for (;;) {
    for (int c = 0; c < 2; ++c) {
      const auto i = static_cast<std::size_t>(c);
      if (have_[i]) continue;
      auto r = grab(c, head_[i], head_t_[i]);
      if (!r || !*r) return r;
      have_[i] = true;
    }
    const TimeNs dt = head_t_[0] - head_t_[1];
    if (std::abs(dt) <= tolerance_ns_) break;
    const std::size_t older = dt < 0 ? 0 : 1;
    have_[older] = false;
    ++dropped_[older];
    if (++drops_in_row > max_drops_)
      return Status::ioError("cameras not synchronised: " + std::to_string(drops_in_row) +
                             " frames dropped in a row, last heads " +
                             std::to_string(std::abs(dt) / kNsPerUs) + " us apart");
  }
  std::swap(left, head_[0]);
  std::swap(right, head_[1]);
  t_ns = head_t_[0];
  have_ = {false, false};
  return true;
}

namespace {

std::vector<std::string> cameraNames(const std::vector<std::unique_ptr<V4l2Capture>>& caps) {
  std::vector<std::string> names;
  for (const auto& c : caps) names.push_back(c->params().device);
  return names;
}

std::string secondsText(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", s);
  return buf;
}

}  // namespace

V4l2StereoSource::V4l2StereoSource(std::vector<std::unique_ptr<V4l2Capture>> captures,
                                   StereoRectification rect, V4l2SourceOptions options)
    : captures_(std::move(captures)),
      rect_(std::move(rect)),
      options_(std::move(options)),
      clock_(options_.clock ? options_.clock : &systemReconnectClock()),
      pairer_(options_.sync_tolerance_ns),
      frozen_(options_.frozen, cameraNames(captures_)) {}

Result<bool> V4l2StereoSource::grabRaw(TimeNs& t_ns) {
  std::uint32_t seq = 0;
  if (captures_.size() == 1) {
    auto r = captures_[0]->grab(full_, t_ns, seq);
    if (!r || !*r) return r;
    return true;
  }
  return pairer_.next(
      [this, &seq](int c, ImageU8& img, TimeNs& t) {
        return captures_[static_cast<std::size_t>(c)]->grab(img, t, seq);
      },
      raw_left_, raw_right_, t_ns);
}

void V4l2StereoSource::warn(const std::string& line) {
  std::lock_guard<std::mutex> lock(warn_mutex_);
  warnings_ += line + "\n";
}

std::string V4l2StereoSource::takeWarnings() {
  std::lock_guard<std::mutex> lock(warn_mutex_);
  std::string w;
  w.swap(warnings_);
  return w;
}

Result<bool> V4l2StereoSource::reconnect(const Status& unplugged) {
  const ReconnectParams& rp = options_.reconnect;
  for (auto& c : captures_) (void)c->stop();
  pairer_.reset();
  frozen_.reset();
  const TimeNs start = clock_->nowNs();
  // Unplugged again before a pair came through: the same outage, the same deadline.
  if (!reconnected_) {
    ++reconnects_;
    outage_start_ns_ = start;
    warn(unplugged.message() + ": reconnecting (every " + std::to_string(rp.interval_ms) +
         " ms for up to " + secondsText(rp.timeout_s) + " s)");
  }
  reconnected_ = false;
  const TimeNs deadline = outage_start_ns_ + secondsToNs(rp.timeout_s);
  const TimeNs interval = rp.interval_ms * kNsPerMs;
  for (int attempt = 1;; ++attempt) {
    if (options_.stop && options_.stop()) {
      reconnect_wait_ns_ += clock_->nowNs() - start;
      return false;
    }
    Status s;
    for (auto& c : captures_) {
      s = c->open();
      if (!s) break;
    }
    const TimeNs now = clock_->nowNs();
    if (s) {
      reconnect_wait_ns_ += now - start;
      reconnected_ = true;
      warn("reconnected " + captures_[0]->params().device +
           (captures_.size() > 1 ? "," + captures_[1]->params().device : "") + " after " +
           std::to_string((now - outage_start_ns_) / kNsPerMs) + " ms");
      return true;
    }
    for (auto& c : captures_) (void)c->stop();
    if (now >= deadline) {
      reconnect_wait_ns_ += now - start;
      return Status::ioError(unplugged.message() + " (not back within " +
                             secondsText(rp.timeout_s) + " s, " + std::to_string(attempt) +
                             " attempts; last: " + s.message() + ")");
    }
    if (clock_->waitNs(std::min(interval, deadline - now), options_.stop)) {
      reconnect_wait_ns_ += clock_->nowNs() - start;
      return false;
    }
  }
}

void V4l2StereoSource::loseRight(const Status& unplugged) {
  (void)captures_[1]->stop();
  right_lost_ = true;
  ++right_losses_;
  right_lost_since_ns_ = clock_->nowNs();
  next_right_attempt_ns_ = right_lost_since_ns_ + options_.reconnect.interval_ms * kNsPerMs;
  warn(unplugged.message() + ": going on with the left camera alone (reopening the right one "
       "every " + std::to_string(options_.reconnect.interval_ms) + " ms)");
}

Result<bool> V4l2StereoSource::nextLeftOnly(StereoFrame& out) {
  const TimeNs now = clock_->nowNs();
  if (now >= next_right_attempt_ns_) {
    if (captures_[1]->open()) {
      right_lost_ = false;
      pairer_.reset();
      frozen_.reset();
      warn("right camera back: " + captures_[1]->params().device + " after " +
           std::to_string((now - right_lost_since_ns_) / kNsPerMs) + " ms");
      return next(out);
    }
    (void)captures_[1]->stop();
    next_right_attempt_ns_ = now + options_.reconnect.interval_ms * kNsPerMs;
  }
  TimeNs t_ns = 0;
  std::uint32_t seq = 0;
  auto r = captures_[0]->grab(raw_left_, t_ns, seq);
  if (r) {
    if (!*r) return r;
    ++left_only_frames_;
    return deliver(t_ns, true, out);
  }
  if (!captures_[0]->unplugged() || options_.reconnect.timeout_s <= 0.0) return r;
  // The left camera gone too: both are reopened together.
  right_lost_ = false;
  auto back = reconnect(r.status());
  if (!back || !*back) return back;
  return next(out);
}

Result<bool> V4l2StereoSource::next(StereoFrame& out) {
  if (right_lost_) return nextLeftOnly(out);
  TimeNs t_ns = 0;
  for (;;) {
    auto r = grabRaw(t_ns);
    if (r) {
      if (!*r) return r;
      break;
    }
    if (options_.right_loss_left_only && captures_.size() == 2 && captures_[1]->unplugged() &&
        !captures_[0]->unplugged()) {
      loseRight(r.status());
      // The left frame that was waiting for its partner is the first one flown alone.
      const bool have_left = pairer_.takeHead(0, raw_left_, t_ns);
      pairer_.reset();
      if (have_left) {
        ++left_only_frames_;
        return deliver(t_ns, true, out);
      }
      return nextLeftOnly(out);
    }
    const bool unplugged = std::any_of(captures_.begin(), captures_.end(),
                                       [](const auto& c) { return c->unplugged(); });
    if (!unplugged || options_.reconnect.timeout_s <= 0.0) return r;
    auto back = reconnect(r.status());
    if (!back || !*back) return back;
  }
  return deliver(t_ns, false, out);
}

Result<bool> V4l2StereoSource::deliver(TimeNs t_ns, bool left_only, StereoFrame& out) {
  std::string warning;
  if (captures_.size() == 1) {
    if (Status s = frozen_.check(0, full_.cview(), warning); !s) return s;
    if (Status s = splitSideBySide(full_, raw_left_, raw_right_); !s) return s;
  } else {
    for (int c = 0; c < (left_only ? 1 : 2); ++c)
      if (Status s = frozen_.check(c, (c == 0 ? raw_left_ : raw_right_).cview(), warning); !s)
        return s;
  }
  if (!warning.empty()) warn(warning);
  if (reconnected_ && have_last_t_) {
    const double fps =
        captures_[0]->grantedFps() > 0.0 ? captures_[0]->grantedFps() : captures_[0]->params().fps;
    const double periods = nsToSeconds(t_ns - last_t_ns_) * fps;
    if (periods > 1.0) frames_lost_ += static_cast<std::uint64_t>(std::llround(periods)) - 1;
  }
  reconnected_ = false;
  have_last_t_ = true;
  last_t_ns_ = t_ns;
  if (Status s = left_only ? rect_.applyLeft(raw_left_, out) : rect_.apply(raw_left_, raw_right_, out);
      !s)
    return s;
  out.index = index_++;
  out.t_ns = t_ns;
  return true;
}

std::vector<std::pair<std::string, std::int64_t>> V4l2StereoSource::counters() const {
  std::vector<std::pair<std::string, std::int64_t>> c;
  auto add = [&c](const std::string& name, std::uint64_t v) {
    c.emplace_back(name, static_cast<std::int64_t>(v));
  };
  add("reconnects", reconnects_);
  add("reconnect_frames_lost", frames_lost_);
  add("reconnect_wait_ms", static_cast<std::uint64_t>(reconnect_wait_ns_ / kNsPerMs));
  if (options_.right_loss_left_only) {
    add("right_losses", right_losses_);
    add("left_only_frames", left_only_frames_);
  }
  for (std::size_t i = 0; i < captures_.size(); ++i) {
    const std::string p = captures_.size() == 1 ? "sbs_" : (i == 0 ? "left_" : "right_");
    const V4l2CaptureStats& st = captures_[i]->stats();
    add(p + "frames", st.frames);
    add(p + "dropped", st.dropped);
    add(p + "retries", st.retries);
    add(p + "non_monotonic", st.non_monotonic);
    add(p + "sequence_gaps", st.sequence_gaps);
    add(p + "software_timestamps", st.software_timestamps);
    if (captures_.size() == 2) add(p + "unpaired", pairer_.dropped(static_cast<int>(i)));
    add(p + "frozen", frozen_.detections(static_cast<int>(i)));
    add(p + "max_identical_run", static_cast<std::uint64_t>(frozen_.maxRun(static_cast<int>(i))));
  }
  return c;
}

Result<FrozenCameraParams> parseFrozenOptions(const CameraSpec& spec, const std::string& scheme) {
  FrozenCameraParams p;
  auto frames = integer(spec, "frozen_frames", p.detector.frozen_frames, scheme);
  if (!frames) return frames.status();
  p.detector.frozen_frames = *frames;
  if (Status s = p.detector.validate(); !s)
    return Status::invalidArgument(scheme + ": option " + s.message());
  if (auto it = spec.options.find("frozen_action"); it != spec.options.end()) {
    if (it->second != "error" && it->second != "warn")
      return Status::invalidArgument(
          scheme + ": option frozen_action must be 'error' or 'warn', got '" + it->second + "'");
    p.end_run = it->second == "error";
  }
  return p;
}

Result<V4l2Setup> parseV4l2Setup(const std::string& spec_after_prefix) {
  auto spec = parseCameraSpec(spec_after_prefix, "v4l2",
                              {"width", "height", "fps", "format", "calib", "sync_ms", "layout",
                               "buffers", "timeout_ms", "max_bad_buffers", "reconnect_timeout_s",
                               "reconnect_interval_ms", "frozen_frames", "frozen_action",
                               "right_loss"});
  if (!spec) return spec.status();
  V4l2CaptureParams p;
  ReconnectParams rp;
  auto width = integer(*spec, "width", p.width, "v4l2");
  auto height = integer(*spec, "height", p.height, "v4l2");
  auto fps = number(*spec, "fps", p.fps, "v4l2");
  auto sync_ms = number(*spec, "sync_ms", 5.0, "v4l2");
  auto buffers = integer(*spec, "buffers", p.buffers, "v4l2");
  auto timeout = integer(*spec, "timeout_ms", p.timeout_ms, "v4l2");
  auto bad = integer(*spec, "max_bad_buffers", p.max_bad_buffers, "v4l2");
  auto rec_timeout = number(*spec, "reconnect_timeout_s", rp.timeout_s, "v4l2");
  auto rec_interval = integer(*spec, "reconnect_interval_ms", rp.interval_ms, "v4l2");
  for (const Status* s :
       {&width.status(), &height.status(), &fps.status(), &sync_ms.status(), &buffers.status(),
        &timeout.status(), &bad.status(), &rec_timeout.status(), &rec_interval.status()})
    if (!*s) return *s;
  auto frozen = parseFrozenOptions(*spec, "v4l2");
  if (!frozen) return frozen.status();
  if (!(*rec_timeout >= 0.0 && *rec_timeout <= 3600.0))
    return Status::invalidArgument("v4l2: option reconnect_timeout_s must be in [0, 3600] s, got " +
                                   spec->options.at("reconnect_timeout_s"));
  if (*rec_interval < 10 || *rec_interval > 60000)
    return Status::invalidArgument(
        "v4l2: option reconnect_interval_ms must be in [10, 60000] ms, got " +
        spec->options.at("reconnect_interval_ms"));
  if (*bad < 0 || *bad > 10000)
    return Status::invalidArgument("v4l2: option max_bad_buffers must be in [0, 10000], got " +
                                   spec->options.at("max_bad_buffers"));
  const auto& opt = spec->options;
  const std::string right_loss = opt.count("right_loss") ? opt.at("right_loss") : "reconnect";
  if (right_loss != "reconnect" && right_loss != "left_only")
    return Status::invalidArgument(
        "v4l2: option right_loss must be 'reconnect' or 'left_only', got '" + right_loss + "'");
  const std::string layout = opt.count("layout") ? opt.at("layout") : "stereo";
  if (layout != "stereo" && layout != "side-by-side")
    return Status::invalidArgument("v4l2: layout must be 'stereo' or 'side-by-side', got '" +
                                   layout + "'");
  const bool sbs = layout == "side-by-side";
  const std::size_t want = sbs ? 1 : 2;
  if (spec->devices.size() != want)
    return Status::invalidArgument(
        "v4l2: " +
        std::string(sbs ? "layout=side-by-side takes one device"
                        : "two devices needed (DEV_LEFT,DEV_RIGHT) unless "
                          "layout=side-by-side") +
        ", got " + std::to_string(spec->devices.size()));
  if (!(*sync_ms >= 0.0 && *sync_ms <= 1000.0))
    return Status::invalidArgument("v4l2: sync_ms must be in [0, 1000]");
  p.width = *width;
  p.height = *height;
  p.fps = *fps;
  p.buffers = *buffers;
  p.timeout_ms = *timeout;
  p.max_bad_buffers = *bad;
  if (opt.count("format")) p.format = opt.at("format");
  if (sbs && p.width % 2 != 0)
    return Status::invalidArgument("v4l2: side-by-side width must be even");
  for (const std::string& d : spec->devices) {
    p.device = d;
    if (Status s = p.validate(); !s) return s;
  }
  V4l2Setup setup;
  setup.params = p;
  setup.devices = spec->devices;
  setup.side_by_side = sbs;
  setup.sync_tolerance_ns =
      static_cast<TimeNs>(std::llround(*sync_ms * static_cast<double>(kNsPerMs)));
  setup.reconnect.timeout_s = *rec_timeout;
  setup.reconnect.interval_ms = *rec_interval;
  if (sbs && right_loss == "left_only")
    return Status::invalidArgument(
        "v4l2: right_loss=left_only needs two cameras (layout=stereo): a side-by-side device "
        "loses both views at once");
  setup.right_loss_left_only = right_loss == "left_only";
  setup.frozen = *frozen;
  if (opt.count("calib")) setup.calib = opt.at("calib");
  return setup;
}

Result<std::vector<std::unique_ptr<V4l2Capture>>> openV4l2Captures(const V4l2Setup& setup,
                                                                   V4l2Device& device) {
  std::vector<std::unique_ptr<V4l2Capture>> caps;
  V4l2CaptureParams p = setup.params;
  for (const std::string& d : setup.devices) {
    p.device = d;
    caps.push_back(std::make_unique<V4l2Capture>(device, p));
    if (Status s = caps.back()->open(); !s) return s;
  }
  return caps;
}

Result<std::unique_ptr<StereoSource>> openV4l2Source(const std::string& spec_after_prefix,
                                                     V4l2Device& device, const StopQuery& stop,
                                                     ReconnectClock* clock) {
  auto setup = parseV4l2Setup(spec_after_prefix);
  if (!setup) return setup.status();
  if (setup->calib.empty())
    return Status::invalidArgument(
        "v4l2: calib=FILE is required (stereo calibration, see docs/cameras.md)");
  auto rect = loadStereoRectification(setup->calib, setup->viewWidth(), setup->params.height);
  if (!rect) return rect.status();
  auto caps = openV4l2Captures(*setup, device);
  if (!caps) return caps.status();
  V4l2SourceOptions o;
  o.sync_tolerance_ns = setup->sync_tolerance_ns;
  o.reconnect = setup->reconnect;
  o.right_loss_left_only = setup->right_loss_left_only;
  o.frozen = setup->frozen;
  o.stop = stop;
  o.clock = clock;
  return std::unique_ptr<StereoSource>(std::make_unique<V4l2StereoSource>(
      std::move(caps).value(), std::move(rect).value(), std::move(o)));
}

Result<std::unique_ptr<StereoSource>> openV4l2Source(const std::string& spec_after_prefix,
                                                     const StopQuery& stop) {
  return openV4l2Source(spec_after_prefix, systemV4l2Device(), stop);
}

}  // namespace svslam::drivers
