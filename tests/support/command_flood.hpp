#pragma once
// A flood of LCM commands at a fixed rate, for the command flood test
// (tests/pipeline/lcm_pipeline_test.cpp) and its benchmark (bench/bench_command_flood.cpp). The
// messages cycle through five kinds:
//   valid          "resume" with the service's token on the command channel (no effect when
//                  not paused; answered when accepted), seq first_seq, first_seq + 1, ...
//   bad token      "shutdown" with another token
//   no token       "shutdown" without a token
//   other channel  "shutdown" with the token on another channel (the service never sees it)
//   malformed      on the command channel, cycling through random bytes (1..64 of them), a
//                  command cut 3 bytes short, a pose_t (another type), and a command_t whose
//                  command is unknown ("launch")
#include <chrono>
#include <cstdint>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "drivers/lcm/lcm_messages.hpp"
#include "drivers/lcm/lcm_transport.hpp"

namespace svslam::test {

struct FloodCounts {
  std::int64_t valid = 0, bad_token = 0, no_token = 0, other_channel = 0, malformed = 0;
  std::int64_t failed_to_send = 0;  // publish errors (none expected)
  double seconds = 0;               // from the first message to the last
  std::int64_t total() const { return valid + bad_token + no_token + other_channel + malformed; }
};

class CommandFlood {
 public:
  // `link` publishes (its params name the command channel); `first_seq` numbers the valid ones.
  CommandFlood(drivers::LcmLink& link, std::string token, std::int64_t first_seq)
      : link_(link), token_(std::move(token)), first_seq_(first_seq), rng_(12345) {}

  static constexpr const char* kOtherChannel = "SVSLAM_COMMAND_ELSEWHERE";

  // Sends `rate_hz` messages a second for `duration` (message k due at start + k / rate; a late
  // sender catches up in a burst, so the count is exact).
  FloodCounts run(double rate_hz, std::chrono::milliseconds duration) {
    FloodCounts c;
    const auto t0 = std::chrono::steady_clock::now();
    const auto period = std::chrono::duration<double>(1.0 / rate_hz);
    const std::int64_t n = static_cast<std::int64_t>(rate_hz * duration.count() / 1000.0);
    for (std::int64_t k = 0; k < n; ++k) {
      std::this_thread::sleep_until(
          t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(period * k));
      if (!send(k, c)) ++c.failed_to_send;
    }
    c.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return c;
  }
  // The valid commands sent have seq in [firstSeq(), firstSeq() + valid).
  std::int64_t firstSeq() const { return first_seq_; }

 private:
  bool send(std::int64_t k, FloodCounts& c) {
    const std::string& ch = link_.params().command_channel;
    drivers::Command cmd{0, 0, drivers::CommandKind::kShutdown, "", ""};
    switch (k % 5) {
      case 0:
        cmd = {0, first_seq_ + c.valid, drivers::CommandKind::kResume, "", token_};
        ++c.valid;
        return link_.publishCommand(cmd).isOk();
      case 1:
        cmd.token = token_ + "-not";
        ++c.bad_token;
        return link_.publishCommand(cmd).isOk();
      case 2:
        ++c.no_token;
        return link_.publishCommand(cmd).isOk();
      case 3: {
        cmd.token = token_;
        ++c.other_channel;
        auto m = drivers::toLcm(cmd);
        return m && drivers::encodeLcm(*m, buf_).isOk() &&
               link_.publishRaw(kOtherChannel, buf_.data(), buf_.size()).isOk();
      }
      default:
        ++c.malformed;
        fillMalformed(c.malformed);
        return link_.publishRaw(ch, buf_.data(), buf_.size()).isOk();
    }
  }
  // The bytes of the i-th malformed message (i from 1), into buf_.
  void fillMalformed(std::int64_t i) {
    switch (i % 4) {
      case 0: {
        buf_.resize(1 + rng_() % 64);
        for (auto& b : buf_) b = static_cast<std::uint8_t>(rng_());
        break;
      }
      case 1: {
        auto m = drivers::toLcm(drivers::Command{0, i, drivers::CommandKind::kReset, "", token_});
        (void)drivers::encodeLcm(*m, buf_);
        buf_.resize(buf_.size() - 3);
        break;
      }
      case 2: {
        drivers::PoseReport p;
        p.seq = i;
        auto m = drivers::toLcm(p);
        (void)drivers::encodeLcm(*m, buf_);
        break;
      }
      default: {
        svslam_lcm::command_t m;
        m.seq = i;
        m.command = "launch";
        m.token = token_;
        (void)drivers::encodeLcm(m, buf_);
      }
    }
  }

  drivers::LcmLink& link_;
  std::string token_;
  std::int64_t first_seq_;
  std::mt19937 rng_;
  std::vector<std::uint8_t> buf_;
};

}  // namespace svslam::test
