#pragma once
// CommandGate: decides whether a received LCM command is carried out. Pure (no clock, no I/O):
// the receive time is passed in.
//
// Order of the checks: commands disabled -> refused (kDisabled); no token in the message ->
// kNoToken; token different from the shared secret (compared in constant time) -> kBadToken;
// more than max_per_s authenticated commands per second (token bucket, burst max_per_s) ->
// kRateLimited; else accepted. Undecodable messages never reach the gate; the link counts them
// as kMalformed (LcmLink::commandCounts). Authentication comes before the rate limit so that
// unauthenticated traffic cannot use up the budget of the authorised sender.
#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "core/status.hpp"
#include "core/token_bucket.hpp"

namespace svslam::drivers {

// The `lcm.commands` configuration.
struct CommandAuthParams {
  bool enabled = false;     // false: every command is refused (kDisabled)
  std::string token_file;   // file holding the shared token; mode must deny group and others
  double max_per_s = 10.0;  // authenticated commands per second (burst of as many), 0.1..1000

  // Error when enabled without a token_file, or max_per_s outside 0.1..1000.
  Status validate() const;
};

enum class CommandRefusal : int { kDisabled, kNoToken, kBadToken, kRateLimited, kMalformed };
inline constexpr int kNumCommandRefusals = 5;
// "disabled", "no_token", "bad_token", "rate_limited", "malformed".
const char* refusalName(CommandRefusal r);

struct CommandCounts {
  std::int64_t accepted = 0;
  std::array<std::int64_t, kNumCommandRefusals> refused{};  // indexed by CommandRefusal

  std::int64_t refusedTotal() const;  // sum of refused, saturated to the int64 range
  std::int64_t refusedBy(CommandRefusal r) const { return refused[static_cast<int>(r)]; }
};

class CommandGate {
 public:
  // Refuses everything (commands disabled).
  CommandGate();
  // enabled: `token` must be non-empty and 0.1 <= max_per_s <= 1000 (else everything is
  // refused as kDisabled). The token is the secret read by readCommandToken().
  CommandGate(bool enabled, std::string token, double max_per_s);

  // Decides on a command received at t_ns carrying `token`, and counts the outcome.
  std::optional<CommandRefusal> admit(const std::string& token, std::int64_t t_ns);

  bool enabled() const { return enabled_; }
  const CommandCounts& counts() const { return counts_; }

 private:
  bool enabled_ = false;
  std::string token_;
  TokenBucket bucket_;
  CommandCounts counts_;
};

}  // namespace svslam::drivers
