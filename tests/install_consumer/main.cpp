// svslam_pose_consumer URL [CHANNEL]: subscribes to svslam's poses (default channel
// SVSLAM_POSE) on the LCM URL, decodes the first one with the installed svslam_lcm::pose_t and
// prints it on one line:
//   pose seq <n> utime <us> frame <id> position <x> <y> <z> (m) orientation <w> <x> <y> <z>
// Exit 0 after one pose; 1 when none arrives within 10 s or a replayed log ends first.
#include <chrono>
#include <cstdio>
#include <string>

#include <lcm/lcm-cpp.hpp>
#include <svslam_lcm/pose_t.hpp>

namespace {

struct PoseHandler {
  bool got = false;
  void onPose(const lcm::ReceiveBuffer*, const std::string&, const svslam_lcm::pose_t* m) {
    if (got) return;
    got = true;
    std::printf("pose seq %lld utime %lld frame %s position %.6f %.6f %.6f orientation %.6f %.6f "
                "%.6f %.6f\n",
                static_cast<long long>(m->seq), static_cast<long long>(m->utime),
                m->frame_id.c_str(), m->position[0], m->position[1], m->position[2],
                m->orientation[0], m->orientation[1], m->orientation[2], m->orientation[3]);
  }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: svslam_pose_consumer URL [CHANNEL]\n");
    return 2;
  }
  const std::string url = argv[1];
  const std::string channel = argc > 2 ? argv[2] : "SVSLAM_POSE";
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "svslam_pose_consumer: cannot open LCM URL '%s'\n", url.c_str());
    return 1;
  }
  PoseHandler handler;
  lcm.subscribe(channel, &PoseHandler::onPose, &handler);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!handler.got && std::chrono::steady_clock::now() < deadline) {
    if (lcm.handleTimeout(100) < 0) break;  // error, or the end of a replayed log
  }
  if (!handler.got) {
    std::fprintf(stderr, "svslam_pose_consumer: no pose on '%s' via '%s'\n", channel.c_str(),
                 url.c_str());
    return 1;
  }
  return 0;
}
