#include "jointsim/common/interrupt.hpp"

#include <atomic>

namespace jointsim {
namespace {
std::atomic<int> g_stop_signal{0};  // lock-free on every platform we build for: usable in a signal handler
static_assert(std::atomic<int>::is_always_lock_free, "the stop flag must be lock-free for signal handlers");
}  // namespace

void requestStop(int signal) noexcept { g_stop_signal.store(signal == 0 ? -1 : signal, std::memory_order_relaxed); }
int stopRequested() noexcept { return g_stop_signal.load(std::memory_order_relaxed); }
void clearStopRequest() noexcept { g_stop_signal.store(0, std::memory_order_relaxed); }

}  // namespace jointsim
