#pragma once
/// \file
/// A Modelica RobotR3 axis driving a 1-D load inertia ([MSL, RobotR3.OneAxis]): op-amp current-controlled motor
/// (drive/opamp_motor.hpp), motor-side bearing friction with the exact MSL stuck/start/sliding logic, motor-side
/// spring–damper, ideal gear, load inertia; the P/PI cascade of [MSL, RobotR3.Utilities.Controller] producing the
/// current set-point; a KinematicPTP2 path; termination at end time + swing time.
///
/// Not a model of its own: a configuration of the RobotR3 robot (systems::RobotR3Full, robotr3_full.hpp) with one
/// type-1 axis (RobotR3AxisParams) driving a fixed load inertia (RobotR3FullSetup::load_inertia: M̄ = J_load, no
/// gravity, no multibody recursion; a single-joint model names the joint), with the energy bookkeeping on and the column names of [MSL, RobotR3.OneAxis]. States (as
/// the Modelica model): q, q̇ (load), φ_rel = ratio·q − φ_m, ω_rel, PI state x, v_C, i; then the four energy
/// integrals W_el = ∫ −5 v_C i dt (work of the power amplifier on the armature circuit), E_R = ∫ Ra i² dt,
/// E_d = ∫ d ω_rel² dt, E_f = ∫ τ_f ω_m dt [J]. Input ports `<prefix>.current` [A] (the current reference held in
/// place of the controller's, its PI frozen) and `<prefix>.load_torque` [N·m] (an external torque on the load, its
/// work not in the energy columns).

#include <string>

#include "jointsim/sim/cvode_integrator.hpp"
#include "jointsim/systems/drive_chain.hpp"
#include "jointsim/systems/robotr3_full.hpp"

namespace jointsim::systems {

struct RobotR3AxisSetup {
  std::string name = "one_axis";
  std::string prefix = "axis";  ///< prefix of the reference column names ("axis" for OneAxis)
  /// The axis's drive: a type-1 axis (elastic gear, motor-side friction) with its controller, the same parameters
  /// (and parameter table, through which faults act) as an axis of the FullRobot. Default: [MSL, RobotR3.OneAxis].
  RobotR3AxisParams axis = RobotR3AxisParams::oneAxis();
  double load_inertia = 19.5;                        ///< J_load [kg·m²]
  double q_begin = 0.0, q_end = 2.0943951023931953;  ///< path [rad]
  double qd_max = 3.0, qdd_max = 10.0;               ///< path limits [rad/s], [rad/s²]
  double start_time = 0.0;                           ///< path start [s]
  double swing_time = 0.5;                           ///< run ends at the first t >= path end + swing [s]
  double stop_time = 1.6;                            ///< requested stop time [s]
  double sa0 = 0.0;               ///< friction torque at t = 0 (undetermined in MSL; docs/validation.md) [N·m]
  double log_interval = 0.00032;  ///< output interval [s]
  sim::CvodeOptions solver = DriveChainSetup::defaultSolver();
  void validate() const;
};

/// The RobotR3 robot of `setup` (validated: InputError with its keys, e.g. `gear.c`, `load.inertia`): one axis on a
/// load, the plant of the `robotr3_axis` experiment type (construct a RobotR3Full from it).
RobotR3FullSetup oneAxisRobot(const RobotR3AxisSetup& setup);

}  // namespace jointsim::systems
