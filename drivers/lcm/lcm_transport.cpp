// LcmLink over the LCM C API (lcm_transport.hpp).
#include "drivers/lcm/lcm_transport.hpp"

#include <glib.h>
#include <lcm/lcm.h>

#include <algorithm>
#include <chrono>
#include <utility>

namespace svslam::drivers {

Status validateChannelName(const std::string& name) {
  if (name.empty()) return Status::invalidArgument("LCM channel name is empty");
  for (char c : name) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-';
    if (!ok)
      return Status::invalidArgument("LCM channel '" + name +
                                     "': use letters, digits, '_' and '-' only");
  }
  if (name.size() > 63) return Status::invalidArgument("LCM channel '" + name + "' is too long");
  return Status::ok();
}

Status LcmParams::validate() const {
  if (url.find("://") == std::string::npos)
    return Status::invalidArgument("LCM URL '" + url +
                                   "' has no provider (use udpm://..., memq:// or file://...)");
  for (const auto* ch : {&pose_channel, &stats_channel, &map_channel, &map_tile_channel,
                         &map_tile_optimized_channel, &correction_channel, &command_channel,
                         &status_channel, &altitude_channel})
    if (Status s = validateChannelName(*ch); !s) return s;
  if (command_channel == status_channel || command_channel == pose_channel)
    return Status::invalidArgument("LCM command channel must differ from the other channels");
  return Status::ok();
}

Result<std::unique_ptr<LcmLink>> LcmLink::open(const LcmParams& params, CommandGate gate) {
  if (Status s = params.validate(); !s) return s;
  lcm_t* lcm = lcm_create(params.url.c_str());
  if (lcm == nullptr) {
    std::string hint;
    if (params.url.rfind("udpm://", 0) == 0)
      hint =
          " (udpm needs a multicast route, e.g. `ip route add 239.0.0.0/8 dev lo`; see "
          "docs/lcm.md)";
    else if (params.url.rfind("file://", 0) == 0)
      hint = " (log file missing, empty or not writable)";
    return Status::ioError("LCM: cannot create an LCM instance for URL '" + params.url + "'" +
                           hint);
  }
  std::unique_ptr<LcmLink> link(new LcmLink(params, lcm, std::move(gate)));
  link->command_sub_ =
      lcm_subscribe(lcm, params.command_channel.c_str(), &LcmLink::commandThunk, link.get());
  if (link->command_sub_ == nullptr)
    return Status::ioError("LCM: cannot subscribe to '" + params.command_channel + "' on '" +
                           params.url + "'");
  lcm_subscription_set_queue_capacity(link->command_sub_, kCommandQueueCapacity);
  return link;
}

LcmLink::LcmLink(LcmParams params, _lcm_t* lcm, CommandGate gate)
    : params_(std::move(params)), lcm_(lcm), gate_(std::move(gate)) {}

LcmLink::~LcmLink() {
  if (lcm_ != nullptr) lcm_destroy(lcm_);  // frees the subscriptions too
}

template <class Msg>
Status LcmLink::publishMsg(const std::string& channel, const Result<Msg>& msg) {
  if (!msg) return msg.status();
  std::lock_guard<std::mutex> lock(publish_mu_);
  if (Status s = encodeLcm(msg.value(), publish_buf_); !s) return s;
  if (lcm_publish(lcm_, channel.c_str(), publish_buf_.data(),
                  static_cast<unsigned int>(publish_buf_.size())) != 0)
    return Status::ioError("LCM: publishing on '" + channel + "' via '" + params_.url + "' failed");
  published_.fetch_add(1);
  return Status::ok();
}

Status LcmLink::publishPose(const PoseReport& r) {
  return publishMsg(params_.pose_channel, toLcm(r));
}
Status LcmLink::publishStats(const StatsReport& r) {
  return publishMsg(params_.stats_channel, toLcm(r));
}
Status LcmLink::publishMap(const MapSummaryReport& r) {
  return publishMsg(params_.map_channel, toLcm(r));
}
Status LcmLink::publishCommandStatus(const CommandStatus& s) {
  return publishMsg(params_.status_channel, toLcm(s));
}
Status LcmLink::publishCommand(const Command& c) {
  return publishMsg(params_.command_channel, toLcm(c));
}
Status LcmLink::publishStereoImage(const std::string& channel,
                                   const svslam_lcm::stereo_image_t& m) {
  if (Status s = validateChannelName(channel); !s) return s;
  if (Status s = validateStereoImage(m); !s) return s;
  return publishMsg(channel, Result<svslam_lcm::stereo_image_t>(m));
}

Status LcmLink::publishRaw(const std::string& channel, const void* data, std::size_t size) {
  if (Status s = validateChannelName(channel); !s) return s;
  std::lock_guard<std::mutex> lock(publish_mu_);
  if (lcm_publish(lcm_, channel.c_str(), data, static_cast<unsigned int>(size)) != 0)
    return Status::ioError("LCM: publishing on '" + channel + "' failed");
  published_.fetch_add(1);
  return Status::ok();
}

void LcmLink::commandThunk(const _lcm_recv_buf_t* rbuf, const char*, void* self) {
  static_cast<LcmLink*>(self)->onCommand(static_cast<const std::uint8_t*>(rbuf->data),
                                         rbuf->data_size);
}

void LcmLink::rawThunk(const _lcm_recv_buf_t* rbuf, const char* channel, void* sub) {
  static_cast<RawSub*>(sub)->fn(std::string_view(channel != nullptr ? channel : ""),
                                static_cast<const std::uint8_t*>(rbuf->data), rbuf->data_size);
}

void LcmLink::onCommand(const std::uint8_t* data, std::size_t size) {
  svslam_lcm::command_t m;
  Status s = decodeLcm(data, size, m);
  Result<Command> c = s ? fromLcm(m) : Result<Command>(s);
  std::lock_guard<std::mutex> lock(pending_mu_);
  if (!c) {
    malformed_.fetch_add(1);
    last_malformed_ = params_.command_channel + ": " + c.status().message();
    return;
  }
  const std::int64_t now_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                  std::chrono::steady_clock::now().time_since_epoch())
                                  .count();
  if (const auto refusal = gate_.admit(c->token, now_ns)) {
    last_refused_ = std::string(refusalName(*refusal)) + ": " + commandName(c->kind) + " seq " +
                    std::to_string(c->seq);
    return;
  }
  if (pending_.size() >= kMaxPendingCommands) {  // nobody polls: keep the newest
    pending_.erase(pending_.begin());
    malformed_.fetch_add(1);
    last_malformed_ = params_.command_channel + ": too many unpolled commands, oldest dropped";
  }
  pending_.push_back(std::move(c.value()));
}

bool LcmLink::takePending(std::vector<Command>& out) {
  std::lock_guard<std::mutex> lock(pending_mu_);
  if (pending_.empty()) return false;
  for (auto& c : pending_) out.push_back(std::move(c));
  pending_.clear();
  return true;
}

CommandCounts LcmLink::commandCounts() const {
  std::lock_guard<std::mutex> lock(pending_mu_);
  CommandCounts c = gate_.counts();
  c.refused[static_cast<int>(CommandRefusal::kMalformed)] = malformed_.load();
  return c;
}

std::string LcmLink::lastRefused() const {
  std::lock_guard<std::mutex> lock(pending_mu_);
  return last_refused_;
}

std::string LcmLink::lastMalformed() const {
  std::lock_guard<std::mutex> lock(pending_mu_);
  return last_malformed_;
}

Result<bool> LcmLink::handleLocked(int timeout_ms) {
  const int r = lcm_handle_timeout(lcm_, std::max(timeout_ms, 0));
  if (r < 0)
    return Status::ioError("LCM: handling messages on '" + params_.url +
                           "' failed (or the replayed log ended)");
  return r > 0;
}

Result<bool> LcmLink::handle(int timeout_ms) {
  if (timeout_ms < 0) return Status::invalidArgument("LcmLink::handle: timeout_ms < 0");
  std::lock_guard<std::mutex> lock(handle_mu_);
  return handleLocked(timeout_ms);
}

Status LcmLink::pollCommands(int timeout_ms, std::vector<Command>& out) {
  if (timeout_ms < 0) return Status::invalidArgument("pollCommands: timeout_ms < 0");
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
  for (;;) {
    // Everything already queued, without waiting (bounded: a sender faster than this cannot
    // keep the caller here).
    for (int i = 0; i < kCommandQueueCapacity; ++i) {
      auto more = handle(0);
      if (!more) return more.status();
      if (!*more) break;
    }
    if (takePending(out)) return Status::ok();
    const auto left_ms =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    const int slice = static_cast<int>(std::clamp<long long>(left_ms, 0, kHandleSliceMs));
    auto r = handle(slice);
    if (!r) return r.status();
    if (left_ms <= 0) {
      takePending(out);
      return Status::ok();
    }
  }
}

Result<int> LcmLink::subscribeRaw(const std::string& channel, RawHandler handler) {
  if (Status s = validateChannelName(channel); !s) return s;
  if (!handler) return Status::invalidArgument("LcmLink::subscribeRaw: empty handler");
  return subscribeEntry(channel,
                        [fn = std::move(handler)](std::string_view, const std::uint8_t* data,
                                                  std::size_t size) { fn(data, size); });
}

Result<int> LcmLink::subscribePattern(const std::string& pattern, ChannelHandler handler) {
  if (pattern.empty()) return Status::invalidArgument("empty channel pattern");
  // LCM matches with GLib's regular expressions: check the pattern with the same engine (std::regex
  // also trips a GCC 12 -Wmaybe-uninitialized false positive in the sanitizer build).
  GError* error = nullptr;
  GRegex* re = g_regex_new(pattern.c_str(), static_cast<GRegexCompileFlags>(0),
                           static_cast<GRegexMatchFlags>(0), &error);
  if (re == nullptr) {
    const std::string why = error != nullptr ? error->message : "invalid";
    if (error != nullptr) g_error_free(error);
    return Status::invalidArgument("channel pattern '" + pattern +
                                   "' is not a regular expression: " + why);
  }
  g_regex_unref(re);
  if (!handler) return Status::invalidArgument("LcmLink::subscribePattern: empty handler");
  return subscribeEntry(pattern, std::move(handler));
}

Result<int> LcmLink::subscribeEntry(const std::string& channel, ChannelHandler handler) {
  std::lock_guard<std::mutex> lock(handle_mu_);
  auto entry = std::make_unique<RawSub>();
  entry->fn = std::move(handler);
  entry->sub = lcm_subscribe(lcm_, channel.c_str(), &LcmLink::rawThunk, entry.get());
  if (entry->sub == nullptr)
    return Status::ioError("LCM: cannot subscribe to '" + channel + "' on '" + params_.url + "'");
  const int id = next_sub_id_++;
  subs_.emplace(id, std::move(entry));
  return id;
}

Status LcmLink::unsubscribe(int id) {
  // handle_mu_: no handler of this link is running while the entry is freed.
  std::lock_guard<std::mutex> lock(handle_mu_);
  auto it = subs_.find(id);
  if (it == subs_.end())
    return Status::invalidArgument("LcmLink::unsubscribe: unknown id " + std::to_string(id));
  lcm_unsubscribe(lcm_, it->second->sub);
  subs_.erase(it);
  return Status::ok();
}

}  // namespace svslam::drivers
