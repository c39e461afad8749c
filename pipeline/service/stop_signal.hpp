#pragma once
// Orderly stop on SIGTERM (systemd's KillSignal), SIGINT (Ctrl-C) and SIGHUP (the terminal or
// the ssh session went away), plus programmatic stop requests (e.g. the LCM "shutdown"
// command).
//
// State is process-wide (signals are): a lock-free std::atomic<int> flag that any thread may poll
// with stopRequested(), and an eventfd that becomes readable on the first stop request so a
// thread blocked in poll()/epoll_wait() wakes up: add stopEventFd() to its poll set with POLLIN.
// Do not read() the eventfd: it stays readable (for every poller) until resetStopRequest().
//
// Handlers are installed with sigaction and without SA_RESTART, so blocking system calls of the
// thread that receives the signal return EINTR instead of resuming.
//
// Double signal: the first SIGTERM/SIGINT/SIGHUP requests the stop; a second one (any of them)
// restores the default action and re-raises itself, so a double Ctrl-C terminates at once even
// if draining hangs. A programmatic requestStop() does not count as a signal.
//
// Async-signal-safety: the handler only touches lock-free atomics and calls write(), sigaction()
// and raise(), all async-signal-safe. requestStop() is async-signal-safe too.
#include "core/status.hpp"

namespace svslam::service {

// Creates the eventfd (once), installs the SIGTERM, SIGINT and SIGHUP handlers and unblocks
// the three signals in the calling thread (a signal that arrived while they were blocked, e.g.
// inherited blocked from the parent, is handled then). Idempotent. Call it first thing, before
// any thread is started (threads inherit the mask). Errors (eventfd or sigaction failing) are
// returned with errno's text.
Status installStopSignalHandlers();

// True once a stop was requested by a signal or by requestStop().
bool stopRequested();

// The signal (SIGTERM = 15, SIGINT = 2, SIGHUP = 1) that first requested the stop; 0 when none
// (no stop yet, or a programmatic requestStop()).
int stopSignalNumber();

// Programmatic stop request from any thread; wakes pollers of stopEventFd().
void requestStop();

// Clears the request, the signal number, the double-signal count and drains the eventfd.
// For tests and for a service that restarts its pipeline in-process.
void resetStopRequest();

// Non-blocking, close-on-exec eventfd that is readable while a stop is requested; created on
// first use (or by installStopSignalHandlers). -1 if the eventfd could not be created.
// Owned by the process: do not close it.
int stopEventFd();

}  // namespace svslam::service
