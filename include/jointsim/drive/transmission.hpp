#pragma once
/// \file
/// Interface of drive-train transmissions: a two-port element between an input shaft (the motor side,
/// angle q_in) and an output shaft (the load/joint side, angle q_out), with optional internal states.
///
/// Sign conventions (used by every drive component and the joint rig):
/// - Angles and velocities are positive in the same rotational sense on both sides; a reducer of ratio
///   N has q_in ≈ N q_out in the unloaded state.
/// - `tau_in` is the torque the transmission exerts AGAINST the input shaft: the motor rotor obeys
///   J_m q̈_in = τ_motor − tau_in − τ_friction,in.
/// - `tau_out` is the torque the transmission DELIVERS to the output shaft: the load obeys
///   J_l q̈_out = tau_out − τ_friction,out − τ_load.
/// - Components are constant after construction; evaluate() is pure (no I/O, no hidden state, no heap
///   allocation) so CVODE may call it at any time and difference it.

#include <memory>
#include <string>
#include <vector>

#include "jointsim/drive/parameters.hpp"

namespace jointsim::drive {

/// Shaft angles [rad] and velocities [rad/s] at the two ports.
struct ShaftPorts {
  double q_in = 0.0;
  double qd_in = 0.0;
  double q_out = 0.0;
  double qd_out = 0.0;
};

/// Torques at the two ports [N·m] (see the sign conventions above).
struct PortTorques {
  double tau_in = 0.0;
  double tau_out = 0.0;
};

class Transmission {
 public:
  virtual ~Transmission() = default;
  /// Short type name for logs and errors ("elastic", "elasto_backlash", "strain_wave_gear", ...).
  virtual std::string type() const = 0;
  /// Nominal ratio N = q_in / q_out (> 0).
  virtual double ratio() const = 0;
  /// True for an ideal rigid gear: it has no evaluate(); the joint rig merges the two shafts.
  virtual bool isRigid() const { return false; }
  /// Number of internal continuous states.
  virtual int stateSize() const { return 0; }
  /// Internal states at static equilibrium (all internal velocities zero) for given shaft angles; writes
  /// stateSize() values to x.
  virtual void initialState(double q_in, double q_out, double* x) const {
    (void)q_in;
    (void)q_out;
    (void)x;
  }
  /// Port torques and internal state derivatives xdot (stateSize() values). Pure.
  virtual PortTorques evaluate(const ShaftPorts& ports, const double* x, double* xdot) const = 0;
  /// Energy stored in the transmission [J]: spring energies plus kinetic energy of internal inertias
  /// (not the shafts' own). Used by passivity tests.
  virtual double storedEnergy(const ShaftPorts& ports, const double* x) const = 0;
  /// Names with units of the internal states, e.g. "q_WG[rad]" (size stateSize()).
  virtual std::vector<std::string> stateNames() const { return {}; }
  /// The parameter table (parameters.hpp): every scalar parameter with its key, unit, range, value and role.
  virtual std::vector<ParameterInfo> parameters() const { return {}; }
  /// The shaft whose units the compliance parameters of the table are in: "motor" or "output" for a gear with one
  /// spring (c_out = N² c_m, b_out = b_m / N, d_out = N² d_m), "" for others.
  virtual std::string complianceSide() const { return {}; }
  /// A new, validated transmission with `changes` (keys of parameters()) applied and every other parameter kept. It
  /// has the same stateSize() and isRigid(), and the same ratio() unless `ratio` is changed; its type() may differ
  /// (an elastic gear given a backlash > 0 becomes an elasto_backlash gear). \throws InputError for an unknown key
  /// or a value the component refuses. The default (a component without a table) refuses every change.
  virtual std::shared_ptr<const Transmission> withParameters(const ParameterChanges& changes) const;
};

}  // namespace jointsim::drive
