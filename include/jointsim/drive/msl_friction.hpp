#pragma once
/// \file
/// The Modelica Standard Library's friction-mode logic (`Rotational.Interfaces.PartialFriction` [MSL]) as free
/// functions, shared by every model with exact stick–slip friction (drive chain, RobotR3 axis and robot,
/// clamped robot): modes stuck / start forward / start backward / forward / backward / free; while stuck the
/// relative acceleration is zero and the friction torque S follows from the torque balance; mode switches are
/// located by two root functions per friction element.

#include <array>
#include <cstddef>
#include <vector>

#include "jointsim/common/bytes.hpp"

namespace jointsim::drive {

/// Friction mode (MSL numbering in the logs: −1 backward, 0 stuck/start, +1 forward, 2 free).
enum class FrictionMode { Stuck, StartForward, StartBackward, Forward, Backward, Free };

/// The root crossings CVODE located at an event for one friction element (slot 0: w or S − τ0max rising;
/// slot 1: S + τ0max falling or the start-phase exit).
struct FrictionEventFlags {
  bool w = false, up = false, down = false, second = false;
};

/// The flags of element k from CVODE's root directions (slots 2k and 2k+1); all false when `fired` is empty
/// (a time event or the initial mode computation).
FrictionEventFlags frictionEventFlags(const std::vector<int>& fired, std::size_t k);

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

}  // namespace jointsim::drive
