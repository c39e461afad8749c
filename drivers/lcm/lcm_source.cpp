// The lcm: stereo source (lcm_source.hpp).
#include "drivers/lcm/lcm_source.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

namespace svslam::drivers {
namespace {

bool sameCalibration(const StereoCalibration& a, const StereoCalibration& b) {
  auto near = [](double x, double y) {
    return std::abs(x - y) <= 1e-9 * std::max(1.0, std::abs(x));
  };
  return a.width == b.width && a.height == b.height && near(a.f_px, b.f_px) &&
         near(a.cx_px, b.cx_px) && near(a.cy_px, b.cy_px) && near(a.baseline_m, b.baseline_m);
}

std::chrono::nanoseconds toDuration(double s) {
  return std::chrono::nanoseconds(static_cast<std::int64_t>(s * 1e9));
}

}  // namespace

Status LcmSourceParams::validate() const {
  if (Status s = validateChannelName(channel); !s)
    return Status::invalidArgument("lcm: " + s.message());
  if (url.find("://") == std::string::npos)
    return Status::invalidArgument("lcm:" + channel + ": bad url '" + url + "'");
  if (!(timeout_s > 0.0 && timeout_s <= 86400.0))
    return Status::invalidArgument("lcm:" + channel + ": timeout_s must be in (0, 86400]");
  if (queue_capacity < 1 || queue_capacity > 256)
    return Status::invalidArgument("lcm:" + channel + ": queue must be in [1, 256]");
  return Status::ok();
}

Result<LcmSourceParams> parseLcmSourceSpec(const std::string& spec) {
  LcmSourceParams p;
  const auto q = spec.find('?');
  p.channel = spec.substr(0, q);
  std::string rest = q == std::string::npos ? "" : spec.substr(q + 1);
  while (!rest.empty()) {
    const auto eq = rest.find('=');
    if (eq == std::string::npos)
      return Status::invalidArgument("lcm:" + spec + ": expected key=value in '" + rest + "'");
    const std::string key = rest.substr(0, eq);
    if (key == "url") {  // takes the rest verbatim
      p.url = rest.substr(eq + 1);
      break;
    }
    const auto amp = rest.find('&', eq);
    const std::string value = rest.substr(eq + 1, amp == std::string::npos ? amp : amp - eq - 1);
    rest = amp == std::string::npos ? "" : rest.substr(amp + 1);
    char* end = nullptr;
    if (key == "timeout_s") {
      p.timeout_s = std::strtod(value.c_str(), &end);
    } else if (key == "queue") {
      p.queue_capacity = static_cast<int>(std::strtol(value.c_str(), &end, 10));
    } else {
      return Status::invalidArgument("lcm:" + spec + ": unknown option '" + key +
                                     "' (use timeout_s, queue, url)");
    }
    if (value.empty() || end == nullptr || *end != '\0')
      return Status::invalidArgument("lcm:" + spec + ": bad value '" + value + "' for " + key);
  }
  if (Status s = p.validate(); !s) return s;
  return p;
}

LcmStereoSource::~LcmStereoSource() {
  stop_.store(true);
  if (rx_.joinable()) rx_.join();
  if (link_ != nullptr && sub_id_ != 0) (void)link_->unsubscribe(sub_id_);
}

void LcmStereoSource::onImage(const std::uint8_t* data, std::size_t size) {
  svslam_lcm::stereo_image_t m;
  Status s = decodeLcm(data, size, m);
  if (s) s = validateStereoImage(m);
  if (!s) {
    malformed_.fetch_add(1);
    return;
  }
  auto c = calibrationOf(m);
  if (!c) {
    malformed_.fetch_add(1);
    return;
  }
  std::lock_guard<std::mutex> lock(mu_);
  if (!have_calib_) {
    calib_ = *c;
    have_calib_ = true;
  } else if (!sameCalibration(calib_, *c)) {
    mismatched_.fetch_add(1);
    return;
  }
  if (queue_.size() >= static_cast<std::size_t>(params_.queue_capacity)) {
    queue_.pop_front();  // keep the newest
    dropped_.fetch_add(1);
  }
  queue_.push_back(std::move(m));
  cv_.notify_all();
}

void LcmStereoSource::receiveLoop() {
  while (!stop_.load()) {
    auto r = link_->handle(LcmLink::kHandleSliceMs);
    if (!r) {
      std::lock_guard<std::mutex> lock(mu_);
      ended_ = true;
      end_status_ = r.status();
      cv_.notify_all();
      return;
    }
  }
}

Status LcmStereoSource::start(LcmLink& link, const StopQuery& stop) {
  link_ = &link;
  auto id = link.subscribeRaw(params_.channel,
                              [this](const std::uint8_t* d, std::size_t n) { onImage(d, n); });
  if (!id) return id.status();
  sub_id_ = *id;
  rx_ = std::thread([this] { receiveLoop(); });
  std::unique_lock<std::mutex> lock(mu_);
  const auto deadline = std::chrono::steady_clock::now() + toDuration(params_.timeout_s);
  for (;;) {
    const auto slice = std::min<std::chrono::steady_clock::time_point>(
        deadline, std::chrono::steady_clock::now() + std::chrono::milliseconds(50));
    if (cv_.wait_until(lock, slice, [this] { return have_calib_ || ended_; })) break;
    if (std::chrono::steady_clock::now() >= deadline) break;
    if (stop && stop())
      return Status::failedPrecondition("lcm:" + params_.channel +
                                        ": stop requested while waiting for the first frame");
  }
  if (have_calib_) return Status::ok();
  std::string why;
  if (ended_) why = " (" + end_status_.message() + ")";
  if (malformed_.load() > 0) why += " (" + std::to_string(malformed_.load()) + " malformed)";
  char secs[32];
  std::snprintf(secs, sizeof secs, "%g", params_.timeout_s);
  return Status::notFound("lcm:" + params_.channel + ": no stereo_image_t received within " + secs +
                          " s" + why);
}

Result<bool> LcmStereoSource::next(StereoFrame& out) {
  svslam_lcm::stereo_image_t m;
  {
    std::unique_lock<std::mutex> lock(mu_);
    cv_.wait_for(lock, toDuration(params_.timeout_s), [this] { return !queue_.empty() || ended_; });
    if (queue_.empty()) return false;  // timeout or end of the stream
    m = std::move(queue_.front());
    queue_.pop_front();
  }
  if (Status s = toStereoFrame(m, out); !s) return s;  // validated on receipt
  out.index = index_++;
  return true;
}

Result<std::unique_ptr<StereoSource>> openLcmSource(const LcmSourceParams& params, LcmLink& link,
                                                    const StopQuery& stop) {
  if (Status s = params.validate(); !s) return s;
  std::unique_ptr<LcmStereoSource> src(new LcmStereoSource(params));
  if (Status s = src->start(link, stop); !s) return s;
  return std::unique_ptr<StereoSource>(std::move(src));
}

Result<std::unique_ptr<StereoSource>> openLcmSource(const std::string& spec_after_prefix,
                                                    const StopQuery& stop) {
  auto params = parseLcmSourceSpec(spec_after_prefix);
  if (!params) return params.status();
  LcmParams lp;
  lp.url = params->url;
  auto link = LcmLink::open(lp);
  if (!link) return link.status();
  std::unique_ptr<LcmStereoSource> src(new LcmStereoSource(*params));
  src->owned_link_ = std::move(link.value());
  if (Status s = src->start(*src->owned_link_, stop); !s) return s;
  return std::unique_ptr<StereoSource>(std::move(src));
}

}  // namespace svslam::drivers
