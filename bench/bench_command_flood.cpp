// The latency cost of an LCM command flood: `svslam run` replays a preloaded synthetic flight at
// a fixed rate with LCM on and commands enabled (token, max_per_s 10), once quiet and once under 1 000
// commands a second (tests/support/command_flood.hpp: valid, wrong token, no token, another
// channel, malformed), alternating, `repeats` times each; prints the end-to-end latency (capture
// -> pose published) of every run from its stats.json and the ratio of the median p99s.
// Budget (docs/lcm.md): flood p99 <= 1.5 x quiet p99 + 2 ms.
//
// Needs a multicast route: run it through scripts/command_flood.sh (a private network namespace).
//   bench_command_flood [frames=150] [rate_hz=10] [repeats=3] [flood_hz=1000] [size=512x384]
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "command_flood.hpp"
#include "drivers/lcm/lcm_messages.hpp"
#include "drivers/lcm/lcm_transport.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using svslam::drivers::CommandKind;
using svslam::drivers::LcmLink;
using svslam::drivers::LcmParams;

namespace {

const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";
const char* kToken = "bench-command-flood-token";

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// The number after `key` following the first `section` in `json` (NaN when absent).
double after(const std::string& json, const std::string& section, const std::string& key) {
  const std::size_t s = json.find(section);
  if (s == std::string::npos) return NAN;
  const std::size_t k = json.find(key, s);
  return k == std::string::npos ? NAN : std::atof(json.c_str() + k + key.size());
}

struct RunResult {
  double p50_ms = NAN, p99_ms = NAN, max_ms = NAN;
  long long dropped = -1, published = -1;
  svslam::test::FloodCounts sent;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[v.size() / 2];
}

RunResult runOnce(const fs::path& dir, const std::string& source, double rate_hz, bool flood,
                  double flood_hz) {
  fs::remove_all(dir / "out");
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = std::string("exec ") + SVSLAM_CLI + " run --config " +
                            (dir / "svslam.yaml").string() + " --preload --source " + source + " --rate " +
                            std::to_string(rate_hz) + " --lcm-url '" + kUrl + "' --out " +
                            (dir / "out").string() + " > " + (dir / "run.log").string() + " 2>&1";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  LcmParams p;
  p.url = kUrl;
  auto link = LcmLink::open(p);
  if (!link) {
    std::fprintf(stderr, "%s\n", link.status().message().c_str());
    std::exit(1);
  }
  std::mutex mu;
  bool answered = false;
  (void)(*link)->subscribeRaw(p.status_channel, [&](const std::uint8_t*, std::size_t) {
    std::lock_guard<std::mutex> lock(mu);
    answered = true;
  });
  std::atomic<bool> stop{false};
  std::thread rx([&] {
    while (!stop.load()) (void)(*link)->handle(50);
  });
  auto exited = [&](int& st) { return ::waitpid(pid, &st, WNOHANG) == pid; };
  int st = 0;
  bool done = false;
  for (int i = 0; i < 100 && !done; ++i) {  // the same handshake quiet or flooded
    {
      std::lock_guard<std::mutex> lock(mu);
      if (answered) break;
    }
    (void)(*link)->publishCommand({0, 1, CommandKind::kResume, "", kToken});
    std::this_thread::sleep_for(300ms);
    done = exited(st);
  }
  RunResult r;
  svslam::test::CommandFlood f(**link, kToken, 1000);
  while (!done) {
    if (flood) {
      const svslam::test::FloodCounts c = f.run(flood_hz, 1000ms);
      r.sent.valid += c.valid;
      r.sent.bad_token += c.bad_token;
      r.sent.no_token += c.no_token;
      r.sent.other_channel += c.other_channel;
      r.sent.malformed += c.malformed;
    } else {
      std::this_thread::sleep_for(100ms);
    }
    done = exited(st);
  }
  stop = true;
  rx.join();
  const std::string stats = slurp(dir / "out" / "stats.json");
  if (!WIFEXITED(st) || WEXITSTATUS(st) != 0 || stats.empty()) {
    std::fprintf(stderr, "svslam run failed:\n%s\n", slurp(dir / "run.log").c_str());
    std::exit(1);
  }
  r.p50_ms = after(stats, "\"end_to_end\"", "\"p50_ms\": ");
  r.p99_ms = after(stats, "\"end_to_end\"", "\"p99_ms\": ");
  r.max_ms = after(stats, "\"end_to_end\"", "\"max_ms\": ");
  r.dropped = static_cast<long long>(after(stats, "\"pipeline\"", "\"frames_dropped\": "));
  r.published = static_cast<long long>(after(stats, "\"pipeline\"", "\"frames_published\": "));
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::atoi(argv[1]) : 150;
  const double rate_hz = argc > 2 ? std::atof(argv[2]) : 10.0;
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 3;
  const double flood_hz = argc > 4 ? std::atof(argv[4]) : 1000.0;
  std::string size = argc > 5 ? argv[5] : "512x384";
  const std::size_t x = size.find('x');
  const std::string source = "synthetic:width=" + size.substr(0, x) +
                             ",height=" + size.substr(x + 1) + ",frames=" + std::to_string(frames);
  const fs::path dir = fs::temp_directory_path() / ("bench_flood_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "command.token") << kToken << "\n";
  ::chmod((dir / "command.token").c_str(), 0600);
  std::ofstream(dir / "svslam.yaml") << "lcm:\n  commands:\n    enabled: true\n    token_file: "
                                     << (dir / "command.token").string() << "\n    max_per_s: 10\n";
  std::printf("source %s at %.1f Hz, flood %.0f commands/s, %d repeats\n", source.c_str(), rate_hz,
              flood_hz, repeats);
  std::printf("%-6s %3s %10s %10s %10s %8s %9s %8s\n", "run", "#", "p50_ms", "p99_ms", "max_ms",
              "dropped", "published", "sent");
  std::vector<double> quiet_p99, flood_p99, quiet_p50, flood_p50;
  for (int i = 0; i < repeats; ++i) {
    for (const bool flood : {false, true}) {
      const RunResult r = runOnce(dir, source, rate_hz, flood, flood_hz);
      std::printf("%-6s %3d %10.2f %10.2f %10.2f %8lld %9lld %8lld\n", flood ? "flood" : "quiet", i,
                  r.p50_ms, r.p99_ms, r.max_ms, r.dropped, r.published,
                  static_cast<long long>(r.sent.total()));
      std::fflush(stdout);
      (flood ? flood_p99 : quiet_p99).push_back(r.p99_ms);
      (flood ? flood_p50 : quiet_p50).push_back(r.p50_ms);
    }
  }
  const double q = median(quiet_p99), f = median(flood_p99);
  std::printf("median p50: quiet %.2f ms, flood %.2f ms\n", median(quiet_p50), median(flood_p50));
  std::printf(
      "median p99: quiet %.2f ms, flood %.2f ms, ratio %.3f; budget 1.5 x %.2f + 2 = %.2f "
      "ms: %s\n",
      q, f, f / q, q, 1.5 * q + 2.0, f <= 1.5 * q + 2.0 ? "within" : "OVER");
  fs::remove_all(dir);
  return 0;
}
