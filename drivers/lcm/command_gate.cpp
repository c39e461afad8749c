#include "drivers/lcm/command_gate.hpp"

#include <cstdint>
#include <utility>

#include "core/constant_time.hpp"

namespace svslam::drivers {

namespace {
constexpr const char* kRefusalNames[kNumCommandRefusals] = {"disabled", "no_token", "bad_token",
                                                            "rate_limited", "malformed"};
constexpr double kMinRate = 0.1, kMaxRate = 1000.0;  // commands per second
}  // namespace

const char* refusalName(CommandRefusal r) { return kRefusalNames[static_cast<int>(r)]; }

Status CommandAuthParams::validate() const {
  if (!(max_per_s >= kMinRate && max_per_s <= kMaxRate))
    return Status::invalidArgument("lcm.commands.max_per_s must be in [0.1, 1000] commands per s");
  if (enabled && token_file.empty())
    return Status::invalidArgument(
        "lcm.commands.enabled is true but lcm.commands.token_file is empty: name the file that "
        "holds the shared token");
  return Status::ok();
}

std::int64_t CommandCounts::refusedTotal() const {
  // Saturated: counts received from the wire (stats_t) may add up past int64.
  std::int64_t n = 0;
  for (std::int64_t r : refused)
    if (__builtin_add_overflow(n, r, &n)) return r > 0 ? INT64_MAX : INT64_MIN;
  return n;
}

CommandGate::CommandGate() : bucket_(1.0, 1.0) {}

CommandGate::CommandGate(bool enabled, std::string token, double max_per_s)
    : enabled_(enabled && !token.empty() && max_per_s >= kMinRate && max_per_s <= kMaxRate),
      token_(std::move(token)),
      bucket_(enabled_ ? max_per_s : 1.0, enabled_ ? max_per_s : 1.0) {}

std::optional<CommandRefusal> CommandGate::admit(const std::string& token, std::int64_t t_ns) {
  std::optional<CommandRefusal> refusal;
  if (!enabled_)
    refusal = CommandRefusal::kDisabled;
  else if (token.empty())
    refusal = CommandRefusal::kNoToken;
  else if (!constantTimeEquals(token, token_))
    refusal = CommandRefusal::kBadToken;
  else if (!bucket_.take(t_ns))
    refusal = CommandRefusal::kRateLimited;
  if (refusal)
    ++counts_.refused[static_cast<int>(*refusal)];
  else
    ++counts_.accepted;
  return refusal;
}

}  // namespace svslam::drivers
