#include "jointsim/sim/hybrid_run.hpp"

#include <algorithm>
#include <chrono>

#include "jointsim/common/error.hpp"

namespace jointsim::sim {

HybridRunResult runHybrid(const HybridSystem& system, const CvodeOptions& options_in, const Eigen::VectorXd& y0,
                          const HybridRunSettings& settings) {
  CvodeOptions options = options_in;
  if (options.max_step == 0.0 && settings.output_interval > 0.0) options.max_step = settings.output_interval;
  const std::function<double(long)> output_time =
      settings.output_time ? settings.output_time : [&settings](long k) {
        return std::min(settings.t_end, static_cast<double>(k) * settings.output_interval);
      };
  if (!(settings.output_interval > 0.0) && !settings.output_time)
    throw InputError("runHybrid: give output_time or an output_interval > 0 s");
  CvodeIntegrator integ(system.n_states, system.rhs, options);
  if (system.n_roots > 0) integ.setRootFunction(system.n_roots, system.roots);
  // Time events inside (0, t_end), then the end itself.
  std::vector<double> breaks;
  for (double b : settings.time_events)
    if (b > 0.0 && b < settings.t_end) breaks.push_back(b);
  std::sort(breaks.begin(), breaks.end());
  breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
  breaks.push_back(settings.t_end);
  size_t next = 0;

  HybridRunResult result;
  const auto start = std::chrono::steady_clock::now();
  Eigen::VectorXd y = y0;
  integ.initialize(0.0, y);
  integ.setStopTime(breaks[0]);
  system.output(0.0, y);
  double t = 0.0;
  for (long k = 1;; ++k) {
    const double t_out = output_time(k);
    long events_here = 0;
    while (t < t_out) {
      t = integ.advance(std::min(t_out, breaks[next]), y);
      const bool at_break = t >= breaks[next] && next + 1 < breaks.size();
      if (integ.rootFound() || at_break) {
        if (at_break) ++next;
        system.on_event(t, y, integ.rootFound() ? integ.rootDirections() : std::vector<int>{});
        integ.initialize(t, y);
        integ.setStopTime(breaks[next]);
        ++result.events;
        if (++events_here > settings.max_events_per_output)
          throw SolverError(options.component + ": more than " + std::to_string(settings.max_events_per_output) +
                                " events in one output interval (chattering) at t = " + std::to_string(t) + " s",
                            t, "EVENT_CHATTERING", options.component);
      }
    }
    system.output(t, y);
    if (settings.n_outputs > 0 ? k >= settings.n_outputs : t_out >= settings.t_end) break;
  }
  result.sim_time_s = t;
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.stats = integ.stats();
  return result;
}

}  // namespace jointsim::sim
