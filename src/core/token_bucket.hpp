#pragma once
// TokenBucket: admits at most `rate_per_s` events per second on average, with bursts of at
// most `burst` events. Pure: the caller passes the time of each event (int64 ns, any
// monotonic clock), so the behaviour is deterministic.
//
// tokens(t) = min(burst, tokens(t_prev) + (t - t_prev) * rate_per_s / 1e9); an event at t is
// admitted when tokens(t) >= 1 and then takes one token. The bucket starts full. A time
// earlier than the previous one adds nothing (no refill backwards).
#include <algorithm>
#include <cstdint>

namespace svslam {

class TokenBucket {
 public:
  // Preconditions: rate_per_s > 0 and finite, burst >= 1.
  TokenBucket(double rate_per_s, double burst)
      : rate_per_s_(rate_per_s), burst_(burst), tokens_(burst) {}

  // True when the event at t_ns is admitted (and takes a token).
  bool take(std::int64_t t_ns) {
    if (!started_) {
      started_ = true;
      last_ns_ = t_ns;
    }
    if (t_ns > last_ns_) {
      const double dt_ns = static_cast<double>(t_ns - last_ns_);
      // (dt * rate) / 1e9: exact whenever dt * rate is a whole number of tokens times 1e9.
      tokens_ = std::min(burst_, tokens_ + dt_ns * rate_per_s_ / 1e9);
      last_ns_ = t_ns;
    }
    if (tokens_ < 1.0) return false;
    tokens_ -= 1.0;
    return true;
  }

  double tokens() const { return tokens_; }  // tokens left after the last take()

 private:
  double rate_per_s_;  // tokens per second
  double burst_;       // bucket size, tokens
  double tokens_;      // tokens at last_ns_
  std::int64_t last_ns_ = 0;
  bool started_ = false;
};

}  // namespace svslam
