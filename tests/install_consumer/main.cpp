// svslam_pose_consumer URL [CHANNEL]: subscribes to svslam's poses (default channel
// SVSLAM_POSE) on the LCM URL, decodes the first one with the installed svslam_lcm::pose_t and
// prints it on one line:
//   pose seq <n> utime <us> frame <id> position <x> <y> <z> (m) orientation <w> <x> <y> <z>
// The same bytes are decoded again with the installed C types (svslam_lcm_pose_t_decode), which
// must agree. Exit 0 after one pose; 1 when none arrives within 10 s, a replayed log ends first
// or the two decoders disagree.
#include <chrono>
#include <cstdio>
#include <string>

#include <lcm/lcm-cpp.hpp>
#include <svslam_lcm/pose_t.hpp>
#include <svslam_lcm_pose_t.h>

namespace {

// True when the C decoder reads the same pose from the bytes.
bool sameInC(const lcm::ReceiveBuffer* rbuf, const svslam_lcm::pose_t& m) {
  svslam_lcm_pose_t c;
  if (svslam_lcm_pose_t_decode(rbuf->data, 0, static_cast<int>(rbuf->data_size), &c) < 0)
    return false;
  bool same = c.seq == m.seq && c.utime == m.utime && std::string(c.frame_id) == m.frame_id;
  for (int i = 0; i < 3; ++i) same = same && c.position[i] == m.position[i];
  for (int i = 0; i < 4; ++i) same = same && c.orientation[i] == m.orientation[i];
  svslam_lcm_pose_t_decode_cleanup(&c);
  return same;
}

struct PoseHandler {
  bool got = false;
  bool c_agrees = false;
  void onPose(const lcm::ReceiveBuffer* rbuf, const std::string&, const svslam_lcm::pose_t* m) {
    if (got) return;
    got = true;
    c_agrees = sameInC(rbuf, *m);
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
  if (!handler.c_agrees) {
    std::fprintf(stderr, "svslam_pose_consumer: the C decoder read another pose\n");
    return 1;
  }
  std::printf("C decoder agrees\n");
  return 0;
}
