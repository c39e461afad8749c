// svslam listen: prints every svslam_lcm message received on LCM (poses, statistics, map
// summaries and tiles, pose corrections, commands and their answers, stereo images), one JSON
// line each (listen_lines.hpp), as received by a separate process.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/lcm/lcm_transport.hpp"
#include "pipeline/cli/arg_parser.hpp"
#include "pipeline/cli/commands.hpp"
#include "pipeline/cli/listen_lines.hpp"

namespace svslam::cli {
namespace {

constexpr ListenType kAllTypes[] = {ListenType::kPose,           ListenType::kStats,
                                    ListenType::kMapSummary,     ListenType::kMapTile,
                                    ListenType::kPoseCorrection, ListenType::kCommand,
                                    ListenType::kCommandStatus,  ListenType::kStereoImage};

// "pose,stats" -> the types; "all" -> every type. Error naming an unknown name.
Result<std::set<ListenType>> parseTypes(const std::string& list) {
  std::set<ListenType> out;
  std::stringstream ss(list);
  std::string name;
  while (std::getline(ss, name, ',')) {
    if (name == "all") {
      out.insert(std::begin(kAllTypes), std::end(kAllTypes));
      continue;
    }
    auto it = std::find_if(std::begin(kAllTypes), std::end(kAllTypes),
                           [&](ListenType t) { return name == listenTypeName(t); });
    if (it == std::end(kAllTypes)) {
      std::string valid = "all";
      for (ListenType t : kAllTypes) valid += std::string(", ") + listenTypeName(t);
      return Status::invalidArgument("unknown message type '" + name + "' (valid: " + valid + ")");
    }
    out.insert(*it);
  }
  if (out.empty()) return Status::invalidArgument("--types names no message type");
  return out;
}

// "poses", "map_tiles", "stats messages": the plural of a type name in messages.
std::string plural(const std::string& type_name) {
  return type_name.back() == 's' ? type_name + " messages" : type_name + "s";
}

}  // namespace

int runListen(const std::vector<std::string>& args) {
  const drivers::LcmParams defaults;
  ArgParser p("listen",
              "Subscribes to the LCM channels matching --channel and prints every svslam_lcm\n"
              "message received as one JSON line on stdout, recognised by its type hash:\n"
              "pose, stats, map_summary, map_tile, pose_correction, command, command_status,\n"
              "stereo_image (fields in docs/lcm.md). Messages of other types are skipped;\n"
              "malformed svslam messages are reported on stderr. Exits 0 after --count\n"
              "messages of --count-type (--count 0: at the end of a replayed file:// log),\n"
              "1 when nothing is printed for --timeout-s or a replayed log ends before --count.");
  p.addOption("url", "URL", "LCM URL", defaults.url);
  p.addOption("channel", "REGEX",
              "channels to print: a name, or a regular expression matching whole names", ".*");
  p.addOption("types", "LIST", "comma-separated message types to print (all: every type)", "all");
  p.addFlag("no-stats", "do not print statistics");
  p.addFlag("no-map-tiles", "do not print map tiles");
  p.addOption("count", "N", "exit 0 after N messages of --count-type (0: never)", "0");
  p.addOption("count-type", "TYPE", "the message type --count counts", "pose");
  p.addOption("timeout-s", "S", "longest wait for the next message printed, seconds", "10");
  if (auto code = parseCommandLine(p, args)) return *code;
  auto fail = [](const Status& s) { return reportFailure("listen", s); };

  auto count = p.getInt("count", 0, 1'000'000'000);
  if (!count) return fail(count.status());
  auto timeout_s = p.getDouble("timeout-s");
  if (!timeout_s) return fail(timeout_s.status());
  if (!(*timeout_s > 0.0 && *timeout_s <= 86400.0))
    return fail(Status::invalidArgument("--timeout-s must be in (0, 86400]"));
  auto types = parseTypes(p.get("types"));
  if (!types) return fail(types.status());
  if (p.flag("no-stats")) types->erase(ListenType::kStats);
  if (p.flag("no-map-tiles")) types->erase(ListenType::kMapTile);
  auto counted_set = parseTypes(p.get("count-type"));
  if (!counted_set) return fail(counted_set.status());
  if (counted_set->size() != 1)
    return fail(Status::invalidArgument("--count-type names one message type"));
  const ListenType counted = *counted_set->begin();
  const std::string counted_name = listenTypeName(counted);
  const std::string pattern = p.get("channel");

  drivers::LcmParams lp;
  lp.url = p.get("url");
  auto link = drivers::LcmLink::open(lp);
  if (!link) return fail(link.status());

  using Clock = std::chrono::steady_clock;
  const auto gap =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(*timeout_s));
  auto deadline = Clock::now() + gap;
  std::int64_t received = 0, malformed = 0;
  const std::int64_t wanted = *count;
  auto on_message = [&](std::string_view channel_view, const std::uint8_t* d, std::size_t n) {
    if (wanted > 0 && received >= wanted) return;
    const ListenType type = listenTypeOf(d, n);
    if (type == ListenType::kUnknown || types->count(type) == 0) return;
    const std::string channel(channel_view);
    const ListenLine line = listenLine(channel, d, n);
    if (line.json.empty()) {
      ++malformed;
      std::fprintf(stderr, "svslam listen: skipped a malformed %s on '%s': %s\n",
                   listenTypeName(type), channel.c_str(), line.error.c_str());
      return;
    }
    std::printf("%s\n", line.json.c_str());
    std::fflush(stdout);
    deadline = Clock::now() + gap;
    if (type == counted) ++received;
  };
  if (auto id = (*link)->subscribePattern(pattern, on_message); !id) return fail(id.status());

  // One message at a time, so that the loop ends right after the N-th counted message (a
  // replayed log may end just after it).
  const bool replay = lp.url.rfind("file://", 0) == 0;
  while (wanted == 0 || received < wanted) {
    const auto left = deadline - Clock::now();
    if (left <= Clock::duration::zero()) {
      char secs[32];
      std::snprintf(secs, sizeof secs, "%g", *timeout_s);
      return fail(Status::notFound(
          "nothing on '" + pattern + "' via '" + lp.url + "' for " + secs + " s (" +
          std::to_string(received) + (wanted ? " of " + std::to_string(wanted) : "") + " " +
          plural(counted_name) + " received, " + std::to_string(malformed) + " malformed)"));
    }
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(left).count();
    auto handled = (*link)->handle(static_cast<int>(std::clamp<long long>(ms, 0, 100)));
    if (!handled && replay && wanted == 0) return 0;  // the whole log was printed
    if (!handled && replay)
      return fail(Status::notFound("the replayed log '" + lp.url + "' ended after " +
                                   std::to_string(received) + " of the " + std::to_string(wanted) +
                                   " " + plural(counted_name) + " wanted (" +
                                   std::to_string(malformed) + " malformed)"));
    if (!handled) return fail(handled.status());
  }
  return 0;
}

}  // namespace svslam::cli
