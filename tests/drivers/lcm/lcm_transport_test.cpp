// LcmLink: poses and commands over memq:// in one process, publishing while another thread
// polls, garbage on the command channel, a udpm pair over loopback multicast in a private
// network namespace, and a file:// log that replays every pose.
#include "drivers/lcm/lcm_transport.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

namespace svslam::drivers {
namespace {

using Clock = std::chrono::steady_clock;

LcmParams memq() {
  LcmParams p;
  p.url = "memq://";
  return p;
}

const char* kToken = "0123456789abcdef-test-token";

// A gate that accepts commands carrying kToken (up to 1000 per second).
CommandGate openGate() { return CommandGate(true, kToken, 1000.0); }

Command cmd(TimeNs t_ns, std::int64_t seq, CommandKind kind, std::string arg = "",
            std::string token = kToken) {
  return {t_ns, seq, kind, std::move(arg), std::move(token)};
}

PoseReport pose(std::int64_t seq) {
  PoseReport r;
  r.seq = seq;
  r.t_ns = 1'000'000'000 + seq * 50'000'000;
  r.publish_t_ns = r.t_ns + 3'000'000;
  r.T_world_cam.linear() =
      Eigen::AngleAxisd(0.01 * double(seq), Eigen::Vector3d::UnitY()).toRotationMatrix();
  r.T_world_cam.translation() = Eigen::Vector3d(0.1 * double(seq), -1.0, 2.0);
  for (int i = 0; i < 6; ++i) r.cov(i, i) = 1e-4 * double(i + 1 + seq);
  r.cov(0, 3) = r.cov(3, 0) = 1e-6;
  return r;
}

// Collects decoded poses of a raw subscription.
struct PoseSink {
  std::mutex mu;
  std::vector<PoseReport> poses;
  int bad = 0;
  LcmLink::RawHandler handler() {
    return [this](const std::uint8_t* d, std::size_t n) {
      svslam_lcm::pose_t m;
      Status s = decodeLcm(d, n, m);
      Result<PoseReport> r = s ? fromLcm(m) : Result<PoseReport>(s);
      std::lock_guard<std::mutex> lock(mu);
      if (r) {
        poses.push_back(r.value());
      } else {
        ++bad;
      }
    };
  }
  std::size_t size() {
    std::lock_guard<std::mutex> lock(mu);
    return poses.size();
  }
};

void expectSamePose(const PoseReport& a, const PoseReport& b) {
  EXPECT_EQ(a.seq, b.seq);
  EXPECT_EQ(a.t_ns, b.t_ns);
  EXPECT_EQ(a.publish_t_ns, b.publish_t_ns);
  EXPECT_TRUE(a.T_world_cam.isApprox(b.T_world_cam, 1e-12));
  EXPECT_EQ(a.cov, b.cov);
  EXPECT_EQ(a.status, b.status);
}

TEST(LcmTransport, ParamsAndOpenErrorsAreClear) {
  LcmParams p;
  EXPECT_TRUE(p.validate().isOk());
  p.pose_channel = "BAD.*";
  EXPECT_FALSE(p.validate().isOk());
  p = LcmParams{};
  p.url = "nonsense";
  EXPECT_FALSE(LcmLink::open(p).isOk());
  p.url = "bogus://nowhere";
  auto link = LcmLink::open(p);
  ASSERT_FALSE(link.isOk());
  EXPECT_NE(link.status().message().find("bogus://nowhere"), std::string::npos);
}

TEST(LcmTransport, MemqPoseReachesSubscriberWithCovariance) {
  auto link = LcmLink::open(memq());
  ASSERT_TRUE(link.isOk()) << link.status().message();
  PoseSink sink;
  ASSERT_TRUE((*link)->subscribeRaw("SVSLAM_POSE", sink.handler()).isOk());
  for (int i = 0; i < 5; ++i) ASSERT_TRUE((*link)->publishPose(pose(i)).isOk());
  PoseReport nan_pose = pose(9);
  nan_pose.cov(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE((*link)->publishPose(nan_pose).isOk());  // never published
  while (true) {
    auto r = (*link)->handle(50);
    ASSERT_TRUE(r.isOk());
    if (!*r) break;
  }
  ASSERT_EQ(sink.size(), 5u);
  for (int i = 0; i < 5; ++i) expectSamePose(sink.poses[std::size_t(i)], pose(i));
  EXPECT_EQ((*link)->published(), 5);
}

TEST(LcmTransport, CommandsArriveThroughPollAndGarbageIsCountedAndIgnored) {
  auto link = LcmLink::open(memq(), openGate());
  ASSERT_TRUE(link.isOk());
  LcmLink& l = **link;
  ASSERT_TRUE(l.publishCommand(cmd(10, 1, CommandKind::kPause)).isOk());
  const std::uint8_t garbage[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  ASSERT_TRUE(l.publishRaw("SVSLAM_COMMAND", garbage, sizeof garbage).isOk());
  ASSERT_TRUE(l.publishRaw("SVSLAM_COMMAND", garbage, 3).isOk());  // truncated
  svslam_lcm::command_t unknown;
  unknown.utime = 0;
  unknown.seq = 2;
  unknown.command = "self_destruct";
  std::vector<std::uint8_t> buf;
  ASSERT_TRUE(encodeLcm(unknown, buf).isOk());
  ASSERT_TRUE(l.publishRaw("SVSLAM_COMMAND", buf.data(), buf.size()).isOk());
  ASSERT_TRUE(l.publishCommand(cmd(20, 3, CommandKind::kSaveMap, "/tmp/m.bin")).isOk());

  std::vector<Command> got;
  const auto t0 = Clock::now();
  while (got.size() < 2 && Clock::now() - t0 < std::chrono::seconds(2))
    ASSERT_TRUE(l.pollCommands(100, got).isOk());
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].kind, CommandKind::kPause);
  EXPECT_EQ(got[1].kind, CommandKind::kSaveMap);
  EXPECT_EQ(got[1].argument, "/tmp/m.bin");
  EXPECT_EQ(got[1].seq, 3);
  EXPECT_EQ(l.malformedCount(), 3);
  EXPECT_NE(l.lastMalformed().find("self_destruct"), std::string::npos);
  // Nothing left: a poll with nothing pending takes about its timeout and returns nothing.
  got.clear();
  const auto t1 = Clock::now();
  ASSERT_TRUE(l.pollCommands(60, got).isOk());
  EXPECT_TRUE(got.empty());
  EXPECT_GE(Clock::now() - t1, std::chrono::milliseconds(55));
}

// Polls until `n` commands were handled (accepted or refused) or 2 s passed.
std::vector<Command> pollAll(LcmLink& l, std::int64_t n) {
  std::vector<Command> got;
  const auto t0 = Clock::now();
  auto handled = [&] {
    const CommandCounts c = l.commandCounts();
    return c.accepted + c.refusedTotal();
  };
  while (handled() < n && Clock::now() - t0 < std::chrono::seconds(2))
    EXPECT_TRUE(l.pollCommands(50, got).isOk());
  EXPECT_TRUE(l.pollCommands(0, got).isOk());
  return got;
}

TEST(LcmTransport, CommandsAreRefusedByDefaultAndCounted) {
  auto link = LcmLink::open(memq());  // default gate: commands disabled
  ASSERT_TRUE(link.isOk());
  LcmLink& l = **link;
  ASSERT_TRUE(l.publishCommand(cmd(0, 1, CommandKind::kShutdown)).isOk());
  ASSERT_TRUE(l.publishCommand(cmd(0, 2, CommandKind::kShutdown, "", "")).isOk());
  const std::vector<Command> got = pollAll(l, 2);
  EXPECT_TRUE(got.empty());
  const CommandCounts c = l.commandCounts();
  EXPECT_EQ(c.accepted, 0);
  EXPECT_EQ(c.refusedBy(CommandRefusal::kDisabled), 2);
  EXPECT_EQ(c.refusedTotal(), 2);
  EXPECT_EQ(l.lastRefused(), "disabled: shutdown seq 2");
}

TEST(LcmTransport, RefusedCommandsAreCountedByReason) {
  auto link = LcmLink::open(memq(), CommandGate(true, kToken, 2.0));  // burst of 2
  ASSERT_TRUE(link.isOk());
  LcmLink& l = **link;
  ASSERT_TRUE(l.publishCommand(cmd(0, 1, CommandKind::kShutdown, "", "")).isOk());
  ASSERT_TRUE(l.publishCommand(cmd(0, 2, CommandKind::kShutdown, "", "wrong")).isOk());
  ASSERT_TRUE(l.publishCommand(cmd(0, 3, CommandKind::kPause)).isOk());
  ASSERT_TRUE(l.publishCommand(cmd(0, 4, CommandKind::kResume)).isOk());
  ASSERT_TRUE(l.publishCommand(cmd(0, 5, CommandKind::kReset)).isOk());  // over the burst
  const std::uint8_t garbage[] = {1, 2, 3};
  ASSERT_TRUE(l.publishRaw("SVSLAM_COMMAND", garbage, sizeof garbage).isOk());
  const std::vector<Command> got = pollAll(l, 6);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].seq, 3);
  EXPECT_EQ(got[1].seq, 4);
  const CommandCounts c = l.commandCounts();
  EXPECT_EQ(c.accepted, 2);
  EXPECT_EQ(c.refusedBy(CommandRefusal::kDisabled), 0);
  EXPECT_EQ(c.refusedBy(CommandRefusal::kNoToken), 1);
  EXPECT_EQ(c.refusedBy(CommandRefusal::kBadToken), 1);
  EXPECT_EQ(c.refusedBy(CommandRefusal::kRateLimited), 1);
  EXPECT_EQ(c.refusedBy(CommandRefusal::kMalformed), 1);
  EXPECT_EQ(l.lastRefused().find("wrong"), std::string::npos);  // never a token in the log
}

TEST(LcmTransport, PublishingWhileAnotherThreadPollsIsNotBlocked) {
  auto link = LcmLink::open(memq(), openGate());
  ASSERT_TRUE(link.isOk());
  LcmLink& l = **link;
  PoseSink sink;
  ASSERT_TRUE(l.subscribeRaw("SVSLAM_POSE", sink.handler()).isOk());
  std::atomic<bool> stop{false};
  std::vector<Command> commands;
  std::thread poller([&] {
    while (!stop.load()) ASSERT_TRUE(l.pollCommands(500, commands).isOk());
  });
  constexpr int kPoses = 100;
  Clock::duration worst{0};
  for (int i = 0; i < kPoses; ++i) {
    const auto t = Clock::now();
    ASSERT_TRUE(l.publishPose(pose(i)).isOk());
    worst = std::max(worst, Clock::now() - t);
    if (i == kPoses / 2) {
      ASSERT_TRUE(l.publishCommand(cmd(0, 77, CommandKind::kReset)).isOk());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const auto t0 = Clock::now();
  while (sink.size() < kPoses && Clock::now() - t0 < std::chrono::seconds(3))
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  stop.store(true);
  poller.join();
  // A publish never waits for the 500 ms poll timeout.
  EXPECT_LT(worst, std::chrono::milliseconds(100));
  ASSERT_EQ(sink.size(), std::size_t(kPoses));  // dispatched by the polling thread
  for (int i = 0; i < kPoses; ++i) EXPECT_EQ(sink.poses[std::size_t(i)].seq, i);
  ASSERT_EQ(commands.size(), 1u);
  EXPECT_EQ(commands[0].seq, 77);
}

TEST(LcmTransport, FileLogReplaysEveryPose) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("svslam_lcm_test_" + std::to_string(getpid()) + ".lcmlog"))
                               .string();
  constexpr int kPoses = 40;
  {
    LcmParams p;
    p.url = "file://" + path + "?mode=w";
    auto writer = LcmLink::open(p);
    ASSERT_TRUE(writer.isOk()) << writer.status().message();
    for (int i = 0; i < kPoses; ++i) ASSERT_TRUE((*writer)->publishPose(pose(i)).isOk());
    StatsReport st;
    st.frames_in = kPoses;
    ASSERT_TRUE((*writer)->publishStats(st).isOk());
  }
  LcmParams p;
  p.url = "file://" + path + "?speed=0";
  auto reader = LcmLink::open(p);
  ASSERT_TRUE(reader.isOk()) << reader.status().message();
  PoseSink sink;
  ASSERT_TRUE((*reader)->subscribeRaw("SVSLAM_POSE", sink.handler()).isOk());
  for (int guard = 0; guard < 10 * kPoses; ++guard) {
    auto r = (*reader)->handle(200);
    if (!r) break;  // end of the log
  }
  std::filesystem::remove(path);
  ASSERT_EQ(sink.size(), std::size_t(kPoses));
  EXPECT_EQ(sink.bad, 0);
  for (int i = 0; i < kPoses; ++i) expectSamePose(sink.poses[std::size_t(i)], pose(i));
}

// Runs inside a private network namespace (see UdpmOverLoopbackMulticast).
TEST(LcmTransport, UdpmInnerPublisherSubscriberPair) {
  if (std::getenv("SVSLAM_LCM_UDPM_INNER") == nullptr)
    GTEST_SKIP() << "runs only inside the namespace made by UdpmOverLoopbackMulticast";
  LcmParams p;  // default udpm URL, ttl=0
  auto pub = LcmLink::open(p);
  ASSERT_TRUE(pub.isOk()) << pub.status().message();
  auto sub = LcmLink::open(p, openGate());
  ASSERT_TRUE(sub.isOk()) << sub.status().message();
  PoseSink sink;
  ASSERT_TRUE((*sub)->subscribeRaw("SVSLAM_POSE", sink.handler()).isOk());
  std::atomic<bool> stop{false};
  std::vector<Command> commands;  // filled by rx, read under commands_mu
  std::mutex commands_mu;
  std::thread rx([&] {
    std::vector<Command> got;
    while (!stop.load()) {
      ASSERT_TRUE((*sub)->pollCommands(50, got).isOk());
      std::lock_guard<std::mutex> lock(commands_mu);
      commands.insert(commands.end(), got.begin(), got.end());
      got.clear();
    }
  });
  auto noCommand = [&] {
    std::lock_guard<std::mutex> lock(commands_mu);
    return commands.empty();
  };
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  constexpr int kPoses = 50;
  for (int i = 0; i < kPoses; ++i) {
    ASSERT_TRUE((*pub)->publishPose(pose(i)).isOk());
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_TRUE((*pub)->publishCommand(cmd(0, 5, CommandKind::kShutdown)).isOk());
  const auto t0 = Clock::now();
  while ((sink.size() < kPoses || noCommand()) && Clock::now() - t0 < std::chrono::seconds(3))
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  stop.store(true);
  rx.join();
  ASSERT_EQ(sink.size(), std::size_t(kPoses));
  for (int i = 0; i < kPoses; ++i) expectSamePose(sink.poses[std::size_t(i)], pose(i));
  ASSERT_EQ(commands.size(), 1u);
  EXPECT_EQ(commands[0].kind, CommandKind::kShutdown);
}

TEST(LcmTransport, UdpmOverLoopbackMulticast) {
  if (std::system("unshare -rn true >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "unshare -rn is not permitted here: cannot make a private network "
                    "namespace with a multicast route";
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  const std::string cmd =
      "unshare -rn sh -c 'ip link set lo up && ip route add 239.0.0.0/8 dev lo && "
      "SVSLAM_LCM_UDPM_INNER=1 exec \"" +
      self + "\" --gtest_filter=LcmTransport.UdpmInnerPublisherSubscriberPair'";
  const int rc = std::system(cmd.c_str());
  EXPECT_EQ(rc, 0) << "inner udpm test failed (output above): " << cmd;
}

}  // namespace
}  // namespace svslam::drivers
