#pragma once
// LcmLink: the service's LCM endpoint. Publishes poses, statistics, map summaries and command
// answers, and receives commands (types and conventions in lcm_messages.hpp, docs/lcm.md).
//
// Threading: any number of threads may publish while one other thread is inside
// pollCommands() / handle(). Publishes are serialised among themselves by a publish mutex
// (the encode buffer is shared, and LCM's file:// writer has no lock of its own); receiving
// uses a different mutex, held only for slices of at most kHandleSliceMs, so a publish never
// waits for a poll timeout. In LCM 1.3 lcm_publish takes no lock shared with lcm_handle: udpm
// serialises sends with its own transmit lock and memq guards its queue with its own mutex.
// Handlers (the command handler and subscribeRaw handlers) run on the thread that is inside
// pollCommands() / handle().
//
// Commands pass a CommandGate (command_gate.hpp) when they are received: only the commands it
// accepts reach pollCommands(); the refused ones are counted by reason (commandCounts()) and
// get no answer.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "core/status.hpp"
#include "drivers/lcm/command_gate.hpp"
#include "drivers/lcm/lcm_messages.hpp"

struct _lcm_t;  // lcm/lcm.h's lcm_t
struct _lcm_subscription_t;
struct _lcm_recv_buf_t;

namespace svslam::drivers {

struct LcmParams {
  // LCM URL: udpm://GROUP:PORT?ttl=N (multicast; ttl=0 keeps traffic on this host),
  // memq:// (in-process only), file:///path.lcmlog?mode=w (write a log), file:///path.lcmlog
  // (replay; ?speed=0 as fast as possible).
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  // Channel names: letters, digits, '_', '-' (LCM treats subscriptions as regular expressions).
  std::string pose_channel = "SVSLAM_POSE";
  std::string stats_channel = "SVSLAM_STATS";
  std::string map_channel = "SVSLAM_MAP";
  std::string map_tile_channel = "SVSLAM_MAP_TILE";
  // The elevation map re-placed after loop-closing corrections (map_tile_t, docs/lcm.md).
  std::string map_tile_optimized_channel = "SVSLAM_MAP_TILE_OPTIMIZED";
  std::string correction_channel = "SVSLAM_POSE_CORRECTION";
  std::string command_channel = "SVSLAM_COMMAND";
  std::string status_channel = "SVSLAM_COMMAND_STATUS";
  // Read (not published): svslam_lcm.altitude_t, the monocular mode's scale source.
  std::string altitude_channel = "SVSLAM_ALTITUDE";

  Status validate() const;
};

// Error unless `name` is a non-empty channel name made of letters, digits, '_' and '-'.
Status validateChannelName(const std::string& name);

class LcmLink {
 public:
  // Longest time the receive mutex is held by one lcm_handle_timeout call, milliseconds.
  static constexpr int kHandleSliceMs = 20;
  // Commands kept between two pollCommands calls; beyond, the oldest is dropped and counted
  // as malformed.
  static constexpr std::size_t kMaxPendingCommands = 256;
  // Messages LCM queues on the command channel until they are handled (LCM's default is 30;
  // beyond, LCM drops them before anyone can count them). At 100 ms between two polls this
  // absorbs 40 000 messages a second, accepted or not.
  static constexpr int kCommandQueueCapacity = 4096;
  // Handler of a raw subscription: the encoded message bytes.
  using RawHandler = std::function<void(const std::uint8_t* data, std::size_t size)>;
  // Handler of a pattern subscription: the channel the message came on and its bytes.
  using ChannelHandler =
      std::function<void(std::string_view channel, const std::uint8_t* data, std::size_t size)>;

  // Creates the LCM instance and subscribes to the command channel; `gate` decides which
  // commands are accepted (default: none). Error naming the URL when LCM cannot be created
  // (e.g. udpm without a multicast route, unwritable log file).
  static Result<std::unique_ptr<LcmLink>> open(const LcmParams& params,
                                               CommandGate gate = CommandGate());
  ~LcmLink();
  LcmLink(const LcmLink&) = delete;
  LcmLink& operator=(const LcmLink&) = delete;

  const LcmParams& params() const { return params_; }

  // Validate (toLcm), encode and publish on the configured channel. Nothing is sent when the
  // report is invalid. Thread-safe.
  Status publishPose(const PoseReport& r);
  Status publishStats(const StatsReport& r);
  Status publishMap(const MapSummaryReport& r);
  Status publishCommandStatus(const CommandStatus& s);
  // For clients and tests: a command on the command channel, an image on `channel`.
  Status publishCommand(const Command& c);
  Status publishStereoImage(const std::string& channel, const svslam_lcm::stereo_image_t& m);
  // Publishes bytes as they are (tests: garbage on the command channel).
  Status publishRaw(const std::string& channel, const void* data, std::size_t size);

  // Handles every message already queued (at most kCommandQueueCapacity), then waits up to
  // timeout_ms (>= 0) for more, and appends the valid commands received and accepted by the
  // gate to `out`. Returns early once at least one command arrived (after draining what is
  // already queued). Malformed or undecodable messages on the command channel are counted
  // (malformedCount) and ignored. Error only when LCM itself fails.
  Status pollCommands(int timeout_ms, std::vector<Command>& out);

  // Subscribes `handler` to `channel` (validateChannelName); returns a subscription id.
  // Must not be called from inside a handler.
  Result<int> subscribeRaw(const std::string& channel, RawHandler handler);
  // Subscribes `handler` to every channel whose whole name matches the regular expression
  // `pattern` (LCM's own matching: GLib/PCRE syntax, anchored at both ends; ".*" = all).
  // Error on an empty pattern or one GLib cannot compile. Must not be called from inside a
  // handler.
  Result<int> subscribePattern(const std::string& pattern, ChannelHandler handler);
  Status unsubscribe(int id);
  // Waits up to timeout_ms (>= 0) for one message and dispatches it to its handlers: true
  // when a message was handled, false on timeout. Error when LCM fails, or at the end of a
  // replayed log file. Commands received here are kept for the next pollCommands.
  Result<bool> handle(int timeout_ms);

  std::int64_t malformedCount() const { return malformed_.load(); }
  std::int64_t published() const { return published_.load(); }
  // Message of the last malformed command ("" when none).
  std::string lastMalformed() const;
  // Commands accepted and refused by reason since open (kMalformed = malformedCount()).
  // Thread-safe.
  CommandCounts commandCounts() const;
  // "<reason>: <command> seq <n>" of the last refused command ("" when none; never the token).
  std::string lastRefused() const;

 private:
  struct RawSub {
    ChannelHandler fn;
    _lcm_subscription_t* sub = nullptr;
  };
  LcmLink(LcmParams params, _lcm_t* lcm, CommandGate gate);
  template <class Msg>
  Status publishMsg(const std::string& channel, const Result<Msg>& msg);
  Result<bool> handleLocked(int timeout_ms);  // precondition: handle_mu_ held
  Result<int> subscribeEntry(const std::string& channel,
                             ChannelHandler handler);  // takes handle_mu_
  void onCommand(const std::uint8_t* data, std::size_t size);
  bool takePending(std::vector<Command>& out);
  static void commandThunk(const _lcm_recv_buf_t* rbuf, const char* channel, void* self);
  static void rawThunk(const _lcm_recv_buf_t* rbuf, const char* channel, void* sub);

  LcmParams params_;
  _lcm_t* lcm_ = nullptr;
  _lcm_subscription_t* command_sub_ = nullptr;

  std::mutex publish_mu_;  // guards publish_buf_ and lcm_publish
  std::vector<std::uint8_t> publish_buf_;

  std::mutex handle_mu_;  // guards lcm_handle and subs_
  std::map<int, std::unique_ptr<RawSub>> subs_;
  int next_sub_id_ = 1;

  mutable std::mutex pending_mu_;  // guards pending_, last_malformed_, gate_, last_refused_
  std::vector<Command> pending_;
  std::string last_malformed_;
  CommandGate gate_;
  std::string last_refused_;

  std::atomic<std::int64_t> malformed_{0};
  std::atomic<std::int64_t> published_{0};
};

}  // namespace svslam::drivers
