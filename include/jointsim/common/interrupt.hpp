#pragma once
/// \file
/// Stopping running simulations from outside, e.g. from a SIGINT/SIGTERM handler: requestStop() sets a flag
/// that sim::simulate() checks at every right-hand-side evaluation and after every output; the run then ends
/// with sim::Interrupted (status "interrupted" in its summary). Async-signal-safe.

namespace jointsim {

/// Asks every running simulation of this process to stop at its next step; `signal` (e.g. SIGINT) is recorded.
void requestStop(int signal) noexcept;
/// The signal of the pending stop request, 0 when there is none.
int stopRequested() noexcept;
/// Clears a stop request.
void clearStopRequest() noexcept;

}  // namespace jointsim
