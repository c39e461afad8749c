#pragma once
// CPU affinity and real-time priority of the calling thread (each pipeline stage thread applies
// its own ThreadScheduling right after it starts), and thread names for top/htop/perf.
//
// Real-time scheduling degrades gracefully: SCHED_FIFO needs CAP_SYS_NICE or RLIMIT_RTPRIO
// (LimitRTPRIO= in the unit), and kernels with CONFIG_RT_GROUP_SCHED (common on ARM boards)
// refuse it to cgroups without an RT budget. In those cases applyToCurrentThread() keeps normal
// scheduling, returns OK and explains in `warning`; it only fails for a configuration that can
// never work (a CPU the machine does not have, a priority outside 1..99).
//
// Real-time threads must block (futex, eventfd, poll), never busy-spin: a spinning SCHED_FIFO
// thread can starve a 2-core machine (docs/platform-notes.md, "Queues and timing").
#include <string>
#include <vector>

#include "core/status.hpp"

namespace svslam::service {

struct ThreadScheduling {
  // CPU indices (0-based, as in /proc/cpuinfo and taskset) the thread may run on; empty = leave
  // the affinity as inherited (all CPUs the process is allowed on).
  std::vector<int> cpus;
  // 0 = normal scheduling (SCHED_OTHER); 1..99 = SCHED_FIFO at that priority (99 highest).
  int fifo_priority = 0;

  // Machine-independent checks: every CPU index in 0..CPU_SETSIZE-1 (1023) and not repeated,
  // fifo_priority in 0..99. Errors name the offending value.
  Status validate() const;
};

// Applies `s` to the calling thread:
//  1. affinity (pthread_setaffinity_np) when s.cpus is non-empty. A CPU index at or beyond the
//     machine's configured CPU count is an error naming the CPU; so is a set none of whose CPUs
//     the process may use (cpuset / CPUAffinity=).
//  2. scheduling (pthread_setschedparam): SCHED_FIFO at s.fifo_priority when > 0; when
//     fifo_priority == 0 and the thread inherited a real-time policy, back to SCHED_OTHER.
//     When SCHED_FIFO is not permitted (EPERM) the thread keeps normal scheduling, the result is
//     OK and `warning` says why and what to grant, e.g.
//       "SCHED_FIFO priority 50 not permitted (EPERM): running with normal scheduling; grant
//        CAP_SYS_NICE or LimitRTPRIO= in the unit"
// `warning` is cleared first and stays empty when everything applied as asked.
Status applyToCurrentThread(const ThreadScheduling& s, std::string& warning);

// Names the calling thread (pthread_setname_np); names longer than 15 bytes are truncated (the
// kernel limit, 16 with the terminating NUL). Failures are ignored: a name is cosmetic.
void setCurrentThreadName(const std::string& name);

}  // namespace svslam::service
