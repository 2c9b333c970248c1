#pragma once
/// \file
/// Interface of friction models acting on one shaft (motor side or output side).
///
/// The friction torque is returned as the torque OPPOSING the motion: a shaft of inertia J obeys
/// J q̈ = τ_driving − τ_friction, so τ_friction > 0 while sliding with v > 0.
/// `driving_torque` is the sum of all other torques on that shaft (used by models with true sticking,
/// e.g. the Modelica BearingFriction semantics; others ignore it). evaluate() is pure and allocation-free.

#include <memory>
#include <string>
#include <vector>

#include "jointsim/drive/parameters.hpp"

namespace jointsim::drive {

struct FrictionInput {
  double v = 0.0;               ///< sliding velocity of the shaft [rad/s]
  double driving_torque = 0.0;  ///< sum of all non-friction torques on the shaft [N·m]
};

class Friction {
 public:
  virtual ~Friction() = default;
  /// Short type name ("coulomb_viscous", "table", "stribeck", "dahl", "lugre", "lugre_ur5").
  virtual std::string type() const = 0;
  /// Number of internal states (bristle deflection z for Dahl and LuGre).
  virtual int stateSize() const { return 0; }
  /// Initial internal state (stateSize() values), at rest: zeros unless documented otherwise.
  virtual void initialState(double* z) const {
    for (int i = 0; i < stateSize(); ++i) z[i] = 0.0;
  }
  /// Friction torque [N·m] (opposing motion) and the internal state derivative zdot. Pure.
  virtual double evaluate(const FrictionInput& in, const double* z, double* zdot) const = 0;
  /// Steady-state friction torque at constant sliding velocity v (the static map) [N·m].
  virtual double steadyState(double v) const = 0;
  /// Whether evaluate() reads FrictionInput::driving_torque (models with true sticking). When false, its result and
  /// zdot are a function of v and z alone, which a caller may memoise (RobotSystem does, per drive, within a run).
  virtual bool readsDrivingTorque() const { return true; }
  /// Names with units of the internal states, e.g. "z[rad]".
  virtual std::vector<std::string> stateNames() const { return {}; }
  /// The parameter table (parameters.hpp): every scalar parameter with its key, unit, range, value and role.
  virtual std::vector<ParameterInfo> parameters() const { return {}; }
  /// A new, validated friction model of the same type and stateSize() with `changes` (keys of parameters()) applied
  /// and every other parameter kept. \throws InputError for an unknown key or a value the model refuses. The
  /// default (a model without a table) refuses every change.
  virtual std::shared_ptr<const Friction> withParameters(const ParameterChanges& changes) const;
};

}  // namespace jointsim::drive
