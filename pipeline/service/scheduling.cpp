#include "pipeline/service/scheduling.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace svslam::service {
namespace {

constexpr int kMaxFifoPriority = 99;

std::string errnoName(int err) {
  switch (err) {
    case EPERM: return "EPERM";
    case EINVAL: return "EINVAL";
    case ESRCH: return "ESRCH";
    default: return std::to_string(err);
  }
}

// Why SCHED_FIFO was refused with EPERM: without privilege, or (privileged enough) because the
// kernel's RT group scheduling gives this cgroup no real-time budget.
std::string fifoRefusedWarning(int priority) {
  std::string w = "SCHED_FIFO priority " + std::to_string(priority) +
                  " not permitted (EPERM): running with normal scheduling; ";
  struct rlimit rl {};
  const bool rlimit_ok = getrlimit(RLIMIT_RTPRIO, &rl) == 0 &&
                         (rl.rlim_cur == RLIM_INFINITY ||
                          rl.rlim_cur >= static_cast<rlim_t>(priority));
  if (geteuid() == 0 || rlimit_ok) {
    w += "the process is privileged enough, so the kernel's RT group scheduling "
         "(CONFIG_RT_GROUP_SCHED) probably gives this cgroup no real-time budget "
         "(cpu.rt_runtime_us = 0); grant one, or run with fifo_priority 0";
  } else {
    w += "grant CAP_SYS_NICE or LimitRTPRIO= in the unit";
  }
  return w;
}

}  // namespace

Status ThreadScheduling::validate() const {
  for (std::size_t i = 0; i < cpus.size(); ++i) {
    if (cpus[i] < 0 || cpus[i] >= CPU_SETSIZE) {
      return Status::invalidArgument("CPU " + std::to_string(cpus[i]) + " out of range 0.." +
                                     std::to_string(CPU_SETSIZE - 1));
    }
    if (std::find(cpus.begin(), cpus.begin() + static_cast<std::ptrdiff_t>(i), cpus[i]) !=
        cpus.begin() + static_cast<std::ptrdiff_t>(i)) {
      return Status::invalidArgument("CPU " + std::to_string(cpus[i]) + " listed twice");
    }
  }
  if (fifo_priority < 0 || fifo_priority > kMaxFifoPriority) {
    return Status::invalidArgument("fifo_priority " + std::to_string(fifo_priority) +
                                   " out of range 0..99 (0 = normal scheduling)");
  }
  return Status::ok();
}

Status applyToCurrentThread(const ThreadScheduling& s, std::string& warning) {
  warning.clear();
  if (Status st = s.validate(); !st) return st;
  const pthread_t self = pthread_self();

  if (!s.cpus.empty()) {
    const long configured = sysconf(_SC_NPROCESSORS_CONF);
    cpu_set_t set;
    CPU_ZERO(&set);
    for (const int cpu : s.cpus) {
      if (configured > 0 && cpu >= configured) {
        return Status::invalidArgument("CPU " + std::to_string(cpu) +
                                       " does not exist: this machine has CPUs 0.." +
                                       std::to_string(configured - 1));
      }
      CPU_SET(cpu, &set);
    }
    if (const int err = pthread_setaffinity_np(self, sizeof(set), &set); err != 0) {
      std::string list;
      for (const int cpu : s.cpus) {
        if (!list.empty()) list += ',';
        list += std::to_string(cpu);
      }
      return Status::invalidArgument("cannot pin the thread to CPUs " + list + " (" +
                                     errnoName(err) + ": " + std::strerror(err) +
                                     "); is the process restricted by a cpuset or CPUAffinity=?");
    }
  }

  int policy = SCHED_OTHER;
  sched_param param{};
  if (const int err = pthread_getschedparam(self, &policy, &param); err != 0) {
    return Status(StatusCode::kInternal,
                  std::string("pthread_getschedparam failed: ") + std::strerror(err));
  }
  if (s.fifo_priority > 0) {
    sched_param fifo{};
    fifo.sched_priority = s.fifo_priority;
    const int err = pthread_setschedparam(self, SCHED_FIFO, &fifo);
    if (err == EPERM) {
      warning = fifoRefusedWarning(s.fifo_priority);
    } else if (err != 0) {
      return Status::invalidArgument("SCHED_FIFO priority " + std::to_string(s.fifo_priority) +
                                     " refused (" + errnoName(err) + ": " + std::strerror(err) +
                                     ")");
    }
  } else if (policy == SCHED_FIFO || policy == SCHED_RR) {
    sched_param normal{};
    normal.sched_priority = 0;
    if (const int err = pthread_setschedparam(self, SCHED_OTHER, &normal); err != 0) {
      return Status(StatusCode::kInternal, std::string("cannot return to SCHED_OTHER: ") +
                                               std::strerror(err));
    }
  }
  return Status::ok();
}

void setCurrentThreadName(const std::string& name) {
  constexpr std::size_t kMaxLen = 15;  // bytes, without the terminating NUL
  const std::string truncated = name.substr(0, kMaxLen);
  pthread_setname_np(pthread_self(), truncated.c_str());
}

}  // namespace svslam::service
