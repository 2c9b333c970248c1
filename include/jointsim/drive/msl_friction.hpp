#pragma once
/// \file
/// The Modelica Standard Library's friction-mode logic (`Rotational.Interfaces.PartialFriction` [MSL]) as free
/// functions, shared by every model with exact stick–slip friction (drive chain, RobotR3 axis and robot,
/// clamped robot): modes stuck / start forward / start backward / forward / backward / free; while stuck the
/// relative acceleration is zero and the friction torque S follows from the torque balance; mode switches are
/// located by two root functions per friction element.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "jointsim/common/bytes.hpp"

namespace jointsim::drive {

/// Friction mode (MSL numbering in the logs: −1 backward, 0 stuck/start, +1 forward, 2 free).
enum class FrictionMode { Stuck, StartForward, StartBackward, Forward, Backward, Free };

/// The root crossings CVODE located at an event for one friction element (slot 0: w or S − τ0max rising;
/// slot 1: S + τ0max falling or the start-phase exit; the normal-force slot: fn rising through zero
/// (`engage`) or falling through it (`release`)).
struct FrictionEventFlags {
  bool w = false, up = false, down = false, second = false;
  bool engage = false, release = false;
};

/// The flags of element k from CVODE's root directions (slots 2k and 2k+1, and `normal_slot` when >= 0, the root
/// of its normal force); all false when `fired` is empty (a time event or the initial mode computation).
FrictionEventFlags frictionEventFlags(const std::vector<int>& fired, std::size_t k, int normal_slot = -1);

/// Whether an element with normal force fn [N] is free (MSL: free = fn <= 0): a crossing located at this event
/// decides (the located point may sit exactly on zero), otherwise the sign of fn.
inline bool frictionFree(double fn, const FrictionEventFlags& fired) {
  if (fired.release) return true;
  if (fired.engage) return false;
  return fn <= 0.0;
}

/// One step of the MSL friction mode logic for one element: current mode m, `free` (normal force <= 0), stuck
/// torque S (valid when m is Stuck) [N·m], sliding speed w [rad/s] and acceleration a [rad/s²], τ0 and τ0max
/// [N·m]; `fired` reports the root crossings located at this event (a located root may sit exactly on its
/// threshold, so the decision follows the reported crossing rather than a strict comparison).
FrictionMode nextFrictionMode(FrictionMode m, bool free, double S, double w, double a, double tau0, double tau0max,
                              const FrictionEventFlags& fired);

/// Root functions g0, g1 of one friction element in mode m (see FrictionEventFlags for the slots).
void frictionRoots(FrictionMode m, double S, double w, double a, double tau0, double tau0max, double& g0, double& g1);

/// Friction torque of a sliding element [N·m]: +f (forward, start forward), −f (backward, start backward), 0
/// (free); `stuck_torque` when stuck.
double frictionTorque(FrictionMode m, double f, double stuck_torque);

/// Mode as logged: −1 backward, 0 stuck or start phase, +1 forward, 2 free (MSL numbering).
int frictionModeNumber(FrictionMode m);

/// MSL friction table (tau_pos rows [w, τ], w ascending) at speed v >= 0: linear interpolation, extrapolated
/// through the end segments; a single row is a constant.
double frictionTableValue(const std::vector<std::array<double, 2>>& table, double v);

/// Friction modes in a saved simulator state (sim::Simulator::saveState): their count, then one number each.
void saveModes(ByteWriter& out, const std::vector<FrictionMode>& modes);
/// Reads what saveModes wrote into `modes`, whose size is the count expected (InputError otherwise, or for a number
/// that is no mode).
void loadModes(ByteReader& in, std::vector<FrictionMode>& modes);

/// One friction element as the mode manager sees it, evaluated at the current modes.
struct FrictionElementView {
  bool friction = true;  ///< false: not a friction element (skipped; its root slots stay unused)
  double S = 0.0;        ///< stuck torque from the torque balance (valid while stuck) [N·m]
  double w = 0.0;        ///< relative sliding speed [rad/s]
  double a = 0.0;        ///< relative acceleration [rad/s²]
  double tau0 = 0.0;     ///< sliding friction at zero speed [N·m]
  double tau0max = 0.0;  ///< break-away friction [N·m], >= tau0
  double fn = 1.0;       ///< normal force [N] (clutch, brake; 1 for friction without one): <= 0 is free
  int normal_slot = -1;  ///< root slot of the normal force, −1: none
};

/// The one event iteration of every model with exact stick–slip friction (the hybrid mode manager): at an event at
/// time t, re-evaluate the model at the current modes (`evaluate()`), take the first element (in element order)
/// whose mode changes by nextFrictionMode (from `view(k)`), change it, and repeat until no element changes — one
/// change per evaluation, because stuck torques are coupled through the torque balance (one element breaking away
/// changes the others' stuck torques). The crossings CVODE located (`fired`, root slots 2k and 2k+1 per element)
/// decide for an element until its mode has changed once in this iteration; afterwards its thresholds decide. The
/// iteration ends after at most 4·n + 8 changes (a chattering cycle ends there with the last modes). Returns the
/// number of mode changes.
template <class Evaluate, class View>
int iterateFrictionModes(FrictionMode* modes, std::size_t n, const std::vector<int>& fired, Evaluate&& evaluate,
                         View&& view) {
  const std::size_t cap = 4 * n + 8;
  std::size_t changes = 0;
  std::uint64_t changed_once = 0;    // elements whose crossings have been used: the first 64 here,
  std::vector<char> changed_beyond;  // the others here (allocated only for chains of more than 64 elements)
  if (n > 64) changed_beyond.assign(n - 64, 0);
  while (changes < cap) {
    evaluate();
    bool changed = false;
    for (std::size_t k = 0; k < n; ++k) {
      const FrictionElementView v = view(k);
      if (!v.friction) continue;
      const bool fresh = k < 64 ? ((changed_once >> k) & 1U) == 0 : changed_beyond[k - 64] == 0;
      const FrictionEventFlags f = fresh ? frictionEventFlags(fired, k, v.normal_slot) : FrictionEventFlags{};
      const FrictionMode m = nextFrictionMode(modes[k], frictionFree(v.fn, f), v.S, v.w, v.a, v.tau0, v.tau0max, f);
      if (m == modes[k]) continue;
      modes[k] = m;
      if (k < 64)
        changed_once |= std::uint64_t{1} << k;
      else
        changed_beyond[k - 64] = 1;
      changed = true;
      break;
    }
    if (!changed) break;
    ++changes;
  }
  return static_cast<int>(changes);
}

}  // namespace jointsim::drive
