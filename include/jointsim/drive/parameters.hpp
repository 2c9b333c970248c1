#pragma once
/// \file
/// Parameter tables of the drive components: every scalar parameter of a transmission, a friction model or a
/// motor with its key, SI unit, admissible range, current value and role, and a way to make a changed copy.
/// Front ends (faults, the FMU, Python, the identification code) read and change components through these tables
/// instead of casting to concrete component types.
///
/// A component is constant: a change of parameters makes a new, validated component (withParameters()). Inside a
/// run that happens only at a documented event: a fault schedule's time event (systems::RobotSystem rebuilds the
/// drives there and restarts the integrator); outside a run, when a model is built (an FMU parameter, a sweep
/// override of the file key). Keys are those of the component's YAML mapping (and of its validation errors), with
/// tables flattened (`tau_pos[2][1]`) and the two friction directions as `positive.alpha0`, `negative.v_s`.

#include <limits>
#include <string>
#include <vector>

namespace jointsim::drive {

/// What a parameter stands for, where several components have one of the kind under different names (the faults
/// act on roles: gear_stiffness_scale on every Stiffness parameter of a transmission, and so on).
enum class ParameterRole {
  None,
  Stiffness,         ///< a stiffness of the gear train (N·m/rad or N/m)
  Backlash,          ///< the total backlash of a gear [rad]
  Coulomb,           ///< the Coulomb (sliding) friction level [N·m] (every table row's torque for table friction)
  BristleStiffness,  ///< the bristle stiffness σ0 of a dynamic friction model [N·m/rad]
  TorqueConstant,    ///< the motor's torque and back-EMF constants k_t [N·m/A], k_e [V·s/rad]
};
/// "none", "stiffness", "backlash", "coulomb", "bristle_stiffness", "torque_constant".
const char* roleName(ParameterRole role);

/// The admissible values of one parameter taken alone: min ≤ v ≤ max with open ends where stated; always finite.
/// Rules that couple parameters (a table's increasing speeds) are checked by the component when it is made.
struct ParameterRange {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;  ///< min itself is excluded
  bool max_open = false;  ///< max itself is excluded
  bool contains(double v) const;
  /// "(0, inf)", "[0, inf)", "[1, inf)", "(0, 1.5708)".
  std::string text() const;
  static ParameterRange positive() { return {0.0, std::numeric_limits<double>::infinity(), true, false}; }
  static ParameterRange nonNegative() { return {0.0, std::numeric_limits<double>::infinity(), false, false}; }
  static ParameterRange atLeast(double v) { return {v, std::numeric_limits<double>::infinity(), false, false}; }
  static ParameterRange above(double v) { return {v, std::numeric_limits<double>::infinity(), true, false}; }
};

/// One row of a component's parameter table.
struct ParameterInfo {
  std::string key;       ///< e.g. "stiffness", "positive.alpha0", "tau_pos[1][1]"
  std::string unit;      ///< SI, "1" for a pure number, e.g. "N·m/rad"
  double value = 0.0;    ///< the component's value
  ParameterRange range;  ///< admissible values on its own
  ParameterRole role = ParameterRole::None;
  std::string description;  ///< what it is, with the source's symbol, e.g. "gear stiffness c (motor side)"
};

/// A change of one parameter by key.
struct ParameterChange {
  std::string key;
  double value = 0.0;
};
using ParameterChanges = std::vector<ParameterChange>;

/// Where a component's table points into its own parameter struct (used by the components' implementations).
struct ParameterRef {
  ParameterInfo info;  ///< value is ignored (read from `target`)
  double* target = nullptr;
};
/// The table of `refs` with the values read from their targets.
std::vector<ParameterInfo> describeParameters(const std::vector<ParameterRef>& refs);
/// Writes every change into its target. \throws InputError naming `component`, the key and the known keys for an
/// unknown key, or the key, value, unit and range for a value outside its range (or not finite).
void assignParameters(const std::vector<ParameterRef>& refs, const ParameterChanges& changes,
                      const std::string& component);

/// The changes that multiply (`add` false) or offset (`add` true) every parameter of role `role` in `table` by
/// `amount`; empty when the table has no parameter of that role.
ParameterChanges roleChanges(const std::vector<ParameterInfo>& table, ParameterRole role, double amount, bool add);
/// True when `table` has a parameter of role `role`.
bool hasRole(const std::vector<ParameterInfo>& table, ParameterRole role);
/// The value of `key` in `table`. \throws InputError naming `component` and the known keys when it has none.
double parameterValue(const std::vector<ParameterInfo>& table, const std::string& key, const std::string& component);

}  // namespace jointsim::drive
