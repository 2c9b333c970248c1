#include "jointsim/common/interrupt.hpp"

#include <signal.h>

#include <atomic>
#include <chrono>

namespace jointsim {
namespace {
std::atomic<int> g_stop_signal{0};  // lock-free on every platform we build for: usable in a signal handler
static_assert(std::atomic<int>::is_always_lock_free, "the stop flag must be lock-free for signal handlers");
thread_local StopPoll* t_poll = nullptr;  // innermost poll of this thread

long long nowNs() noexcept {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

extern "C" void onStopSignal(int sig) { requestStop(sig); }
}  // namespace

void requestStop(int signal) noexcept { g_stop_signal.store(signal == 0 ? -1 : signal, std::memory_order_relaxed); }

int stopRequested() noexcept {
  if (const int sig = g_stop_signal.load(std::memory_order_relaxed)) return sig;
  return t_poll ? t_poll->poll() : 0;
}

void clearStopRequest() noexcept { g_stop_signal.store(0, std::memory_order_relaxed); }

void installStopSignalHandlers() noexcept {
  struct sigaction sa {};
  sa.sa_handler = onStopSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

void forgetStopPolls() noexcept { t_poll = nullptr; }

StopPoll::StopPoll(Check check, void* context, double interval_s) noexcept
    : check_(check),
      context_(context),
      interval_ns_(static_cast<long long>(interval_s > 0.0 ? interval_s * 1e9 : 0.0)),
      outer_(t_poll) {
  t_poll = this;
}

StopPoll::~StopPoll() {
  if (t_poll == this) t_poll = outer_;
}

int StopPoll::poll() noexcept {
  if (tripped_ || !check_) return tripped_;
  const long long now = nowNs();
  if (now < next_ns_) return 0;
  next_ns_ = now + interval_ns_;
  tripped_ = check_(context_);
  return tripped_;
}

}  // namespace jointsim
