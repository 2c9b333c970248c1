#pragma once
/// \file
/// Stopping running simulations from outside.
///
/// - Process-wide: requestStop() (async-signal-safe, e.g. from a SIGINT/SIGTERM handler, see
///   installStopSignalHandlers()) sets a flag that sim::simulate(), sim::Simulator and jointsim batch check at every
///   right-hand-side evaluation and after every output; the run then ends with sim::Interrupted (status
///   "interrupted" in its summary).
/// - Per calling thread: a host that keeps its own record of pending signals (Python's interpreter, whose SIGINT
///   handler only sets a flag that is seen when control returns to it) installs a StopPoll around a long call.
///   stopRequested() then also asks the poll, at most once per interval, and reports its answer; nothing changes for
///   other threads or after the poll is gone.

namespace jointsim {

/// Asks every running simulation of this process to stop at its next step; `signal` (e.g. SIGINT) is recorded.
void requestStop(int signal) noexcept;
/// The signal of the pending stop request (process-wide, or from this thread's StopPoll), 0 when there is none.
int stopRequested() noexcept;
/// Clears the process-wide stop request.
void clearStopRequest() noexcept;

/// SIGINT and SIGTERM call requestStop() (sigaction without SA_RESTART, so a blocking wait returns with EINTR and
/// the caller sees the request): for the command-line tool and for the child processes of jointsim batch.
void installStopSignalHandlers() noexcept;

/// Forgets this thread's StopPolls without calling them: for a child process made by fork(), which inherits the
/// forking thread's polls but not the host they ask (e.g. Python's interpreter, whose lock it must never take).
void forgetStopPolls() noexcept;

/// While alive, stopRequested() on the constructing thread also calls `check(context)` at most once every
/// `interval_s` seconds (wall clock); a non-zero result (the signal, e.g. SIGINT) is a stop request of this thread
/// from then on (sticky for the poll's lifetime). Polls nest; the innermost is asked. `check` runs on the calling
/// thread inside stopRequested() and must not throw.
class StopPoll {
 public:
  using Check = int (*)(void* context) noexcept;
  StopPoll(Check check, void* context, double interval_s = 0.02) noexcept;
  ~StopPoll();
  StopPoll(const StopPoll&) = delete;
  StopPoll& operator=(const StopPoll&) = delete;
  /// The signal the poll reported, 0 while none.
  int tripped() const noexcept { return tripped_; }

 private:
  friend int stopRequested() noexcept;
  int poll() noexcept;
  Check check_;
  void* context_;
  long long interval_ns_;
  long long next_ns_ = 0;
  int tripped_ = 0;
  StopPoll* outer_;
};

}  // namespace jointsim
