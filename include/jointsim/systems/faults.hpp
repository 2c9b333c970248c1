#pragma once
/// \file
/// Fault injection for prognostics data sets: typed, physically meaningful modifications of one drive of
/// a robot with drives (systems::DriveSpec), applied before the system is assembled. Each fault builds new
/// component objects from the old ones' parameters; nothing is mutated in place.
///
/// | type (YAML name)          | value (severity)              | effect                                                     |
/// |---------------------------|-------------------------------|------------------------------------------------------------|
/// | `gear_stiffness_scale`    | factor s, 0 < s <= 100 [-]    | every stiffness of the transmission × s (worn gear)        |
/// | `backlash_add`            | Δb, 0 <= Δb <= 0.5 [rad], transmission's compliance side | total backlash + Δb (an elastic gear becomes elasto-backlash) |
/// | `coulomb_friction_scale`  | factor s, 0 < s <= 100 [-]    | Coulomb level × s: f_c, α0 (both directions), table torques |
/// | `sigma0_scale`            | factor s, 0 < s <= 100 [-]    | bristle stiffness σ0 (LuGre, UR5 LuGre) or Dahl σ × s      |
/// | `torque_constant_scale`   | factor s, 0 < s <= 100 [-]    | motor k_t and k_e × s (demagnetised motor); needs electrics |
/// | `sensor_bias`             | bias, abs <= π [rad]          | offset of the measured joint angle; needs a controller that reads it (voltage_cascade) |
/// | `sensor_dropout`          | episode length w > 0 [s]      | the measured joint angle reads 0 rad during each episode   |
/// | `sensor_stuck`            | episode length w > 0 [s]      | the measured joint angle holds its value from the episode's start |
/// | `sensor_spike`            | amplitude A, abs <= π [rad]   | A added to the measured joint angle during each episode (of `width`) |
/// | `bearing_ripple`          | amplitude A >= 0 [N·m]        | τ_b = A sin(order · φ_out) added to the friction torque of the output shaft |
///
/// Time laws (all types): a fault acts from `onset` [s] on (default 0: from the start).
/// - Parameter faults (the first six and bearing_ripple) follow a progression from the nominal value (factor 1,
///   offset 0) to the severity: `step` (at the onset, the default), `linear` or `exponential` over `ramp_time` T [s],
///       p(τ) = τ/T  (linear),   p(τ) = (e^{λτ} − 1)/(e^{λT} − 1)  (exponential, rate λ > 0 [1/s]),   τ = t − onset,
///   value(t) = nominal + (severity − nominal)·p(τ), the severity from onset + T on (gradual wear, accelerating wear).
///   The drive's components are rebuilt with the value at `steps` instants t_k = onset + kT/steps (k = 0…steps − 1),
///   each holding the law's value at the middle of its interval [t_k, t_k+1), and the severity from onset + T on: a
///   parameter schedule of piecewise-constant values (the integrator restarts at each t_k; default 100 steps,
///   so the value deviates from the continuous law by at most its change over one step, half of it for a linear law).
/// - Intermittent sensor faults (sensor_dropout, sensor_stuck, sensor_spike) occur in episodes starting at
///   onset + k·period (k = 0 … count − 1; period 0: one episode; count 0: until the end), each lasting the
///   episode length (sensor_spike: `width`, default 1 ms); episode edges are time events.
/// - bearing_ripple: a defect of the output bearing; `order` ripple cycles per revolution of the output shaft, so
///   that its frequency is order × the shaft speed / 2π.

#include <limits>
#include <string>
#include <vector>

#include "jointsim/drive/parameters.hpp"

namespace jointsim::systems {

struct DriveSpec;  // robot_system.hpp

enum class FaultType {
  GearStiffnessScale,
  BacklashAdd,
  CoulombFrictionScale,
  Sigma0Scale,
  TorqueConstantScale,
  SensorBias,
  SensorDropout,
  SensorStuck,
  SensorSpike,
  BearingRipple
};

enum class Progression { Step, Linear, Exponential };

struct Fault {
  FaultType type = FaultType::GearStiffnessScale;
  std::string joint;   ///< joint whose drive is affected
  double value = 1.0;  ///< the severity: factor [-], backlash [rad], bias [rad], ... see the table above
  double onset = 0.0;  ///< [s], from when the fault acts
  // Parameter faults and bearing_ripple:
  Progression progression = Progression::Step;
  double ramp_time = 0.0;  ///< T [s] from the onset to the full severity (linear, exponential)
  double rate = 0.0;       ///< λ [1/s] of the exponential progression
  int steps = 100;         ///< parameter updates over the ramp (1 … 100000)
  // Intermittent sensor faults:
  double period = 0.0;  ///< [s] between episode starts (0: a single episode)
  int count = 0;        ///< episodes (0: unlimited, with period > 0)
  double width = 1e-3;  ///< [s] length of a spike episode (sensor_spike)
  // bearing_ripple:
  double order = 1.0;  ///< ripple cycles per output shaft revolution [-], > 0

  /// True for a fault that changes during a run (an onset after 0, a progression, or an intermittent or ripple
  /// type); a constant one is applied to the drive's components before the system is assembled.
  bool timeVarying() const;
  /// True for the parameter faults (rebuilt components, applyFault): the first six types.
  bool parameterFault() const;
  /// True for sensor_dropout, sensor_stuck and sensor_spike.
  bool intermittent() const;
};

const char* toString(FaultType type);
/// Parses a YAML/CLI name (e.g. "gear_stiffness_scale"); throws InputError listing the known names.
FaultType faultTypeFromString(const std::string& name);
/// All fault type names, in the order of the enum.
std::vector<std::string> faultTypeNames();
/// "gear_stiffness_scale@elbow_joint=0.8", with the time law when there is one:
/// "gear_stiffness_scale@elbow_joint=0.6 from 0.5 s linear over 1 s (100 steps)".
std::string describe(const Fault& fault);
/// Checks the fault on its own (severity range of its type, time law): InputError naming the fault.
void checkFault(const Fault& fault);

/// Normalised progress p ∈ [0, 1] of the continuous law at time t (0 before the onset; step: 1 from the onset).
double faultProgress(const Fault& fault, double t);
/// The value of the continuous law at t: nominal + (severity − nominal)·p(t), nominal 1 for factors, 0 otherwise.
double faultValue(const Fault& fault, double t);
/// The value applied at t: the parameter schedule's piecewise-constant value (see the file comment); for the
/// intermittent types the severity.
double scheduledFaultValue(const Fault& fault, double t);
/// The most time events one fault may give a run (episode edges of an intermittent fault).
constexpr long kMaxFaultEvents = 1000000;
/// The instants in (0, t_end) at which the fault's effect jumps: onset, schedule steps, episode edges. InputError when
/// there would be more than kMaxFaultEvents (e.g. a 1e-9 s period), before any is listed.
std::vector<double> faultEvents(const Fault& fault, double t_end);
/// Intermittent faults: whether t lies in an episode [start, start + length), and its index.
bool faultEpisode(const Fault& fault, double t, long* episode = nullptr);

/// Whether a fault of `type` applies to `drive`: its components have a parameter of the fault's role (parameters.hpp:
/// stiffness, backlash, Coulomb level, bristle stiffness; the motor's torque constant needs electrics), or its
/// controller reads the joint angle (the sensor faults). Bearing ripple applies to every drive.
bool faultApplies(const DriveSpec& drive, FaultType type);
/// Applies a parameter fault to `drive` (whose joint must be fault.joint) with `value` (NaN: its severity). Throws
/// InputError when the fault does not apply to the drive's components or its value is out of range. The other
/// types act during the run (RobotSystem::setFaults) and are only checked against the drive here.
void applyFault(DriveSpec& drive, const Fault& fault, double value = std::numeric_limits<double>::quiet_NaN());
/// The changes that apply the parameter fault `fault` (severity `value`; NaN: its severity) to a drive known only by its
/// parameter table (an axis of the clamping or RobotR3 models, whose components are plain parameters): every parameter
/// of the fault's role scaled (or, for backlash_add, offset). InputError naming the fault and `component` when it is no
/// parameter fault, has a time law (these models take constant faults), or the table has no parameter of its role.
drive::ParameterChanges tableFaultChanges(const std::vector<drive::ParameterInfo>& table, const Fault& fault,
                                          const std::string& component,
                                          double value = std::numeric_limits<double>::quiet_NaN());
/// Applies every constant fault to the drive of its joint (the time-varying ones act during the run:
/// RobotSystem::setFaults); throws InputError for a joint without a drive.
void applyFaults(std::vector<DriveSpec>& drives, const std::vector<Fault>& faults);

}  // namespace jointsim::systems
