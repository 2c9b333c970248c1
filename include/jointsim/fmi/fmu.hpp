#pragma once
/// \file
/// FMI 2.0 Co-Simulation export of an experiment (`jointsim fmu FILE.yaml -o NAME.fmu`).
///
/// An FMU is a zip archive: `modelDescription.xml` (the variables, FMI 2.0 schema), `binaries/linux64/NAME.so`
/// (the generic jointsim FMU binary, built from fmu/fmi2_cosimulation.cpp, with every library it needs beside it
/// and found through its RPATH $ORIGIN), and `resources/` with the experiment file, the files it reads (robot,
/// drives, URDF, CSV inputs) in their relative layout, and `jointsim_fmu.json`, the FmuDescription the binary
/// reads at fmi2Instantiate.
///
/// Variables (FmuDescription::variables; value references are their indices):
/// - inputs: command ports (`--inputs`): for an experiment of type `tracking`, `PORT` (every joint) or
///   `JOINT:PORT` with PORT one of voltage [V], current [A], motor_torque [N·m], motor_velocity [rad/s]
///   (systems::CommandPort) named `cmd_<port>_<joint>`, or `setpoint` giving `cmd_q_<joint>` [rad] and
///   `cmd_qd_<joint>` [rad/s]; for a `joint_rig`, `command`: the rig's configured input (motor torque [N·m],
///   voltage [V] or velocity reference [rad/s]) named `cmd_input`. Inputs are held over each communication step.
/// - outputs: the plant's signals (`--outputs NAME,...`; default all), named without their `[unit]`.
/// - parameters (variability fixed: set before fmi2ExitInitializationMode): every number of the experiment file
///   by its key path (e.g. `load.inertia`, `solver.rtol`, `trajectory.a[0,1]`), applied as `--set key.path=value`
///   when it differs from its start, exactly as on the command line; and for a robot with drives, the drive
///   parameters of its robot file as the factors and offsets of systems::Fault (`drives.<joint>.gear_stiffness_scale`,
///   `coulomb_friction_scale`, `sigma0_scale`, `torque_constant_scale` [-], `backlash_add`, `sensor_bias` [rad],
///   those that apply to the drive's components), applied as the same fault of `jointsim batch`.
///
/// fmi2DoStep integrates with sim::Simulator (CVODE's own step control, events and samples inside the step) and
/// ends exactly at the communication point. Every error is returned as fmi2Error (after a failed step the
/// instance only accepts fmi2Reset, fmi2Terminate and fmi2FreeInstance) and logged through the importer's
/// logger with the simulated time and the component; nothing throws across the C interface.

#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace jointsim::experiments {
class Experiment;
}

namespace jointsim::fmi {

enum class Causality { Input, Output, Parameter };

struct Variable {
  std::string name;
  Causality causality = Causality::Output;
  std::string unit;         ///< SI unit ("" for a dimensionless number or an unknown unit)
  std::string description;  ///< one line
  double start = 0.0;       ///< start value (inputs, parameters)
  /// Inputs: the plant's input port (sim::InputPort name, e.g. "elbow_joint.voltage", "command"). Outputs: the
  /// signal's index in the plant's signalNames(). Parameters: the override that sets it (the experiment file's key
  /// path, "+drives.<joint>.<component>.<key>" for a drive parameter); for a fault parameter the joint's name.
  std::string port;
  int signal = -1;
  std::string key;
  /// Drive parameters of a robot with drives: the systems::FaultType name (e.g. "gear_stiffness_scale") applied
  /// to the drive of the joint named by `key` when the value differs from its neutral start (1 for a scale, 0
  /// otherwise).
  std::string fault;
  /// Parameters: the admissible values where they are a closed interval (FMI min/max; ±inf: none).
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  /// Outputs: the input variables (indices in FmuDescription::variables) the output depends on directly (FMI
  /// ModelStructure dependencies), measured at export; `depends_known` false: on all (not written).
  std::vector<int> depends;
  bool depends_known = false;
};

/// A unit in the ASCII notation of FMI unit names and Modelica: N·m → N.m, kg·m² → kg.m2, Ω → Ohm (jointsim's own
/// files and CSV headers keep N·m).
std::string fmuUnit(const std::string& unit);

/// What the FMU binary needs to rebuild the experiment: written to resources/jointsim_fmu.json by the exporter.
struct FmuDescription {
  std::string model_identifier;        ///< the binary's name (NAME.so) and the model name
  std::string guid;                    ///< "{...}" from the content hashes of the description and the input files
  std::string experiment_file;         ///< the experiment file, relative to resources/
  std::string experiment_type;         ///< "tracking" or "joint_rig"
  std::string description;             ///< the experiment's description
  double stop_time = 1.0;              ///< the experiment's duration [s] (DefaultExperiment)
  double step_size = 1e-3;             ///< suggested communication step [s] (DefaultExperiment)
  std::vector<std::string> overrides;  ///< "key.path=value" given at export (applied before the parameters')
  std::vector<Variable> variables;
  /// Numbers of the experiment file not offered as parameters because their unit is unknown (Experiment::keyUnit);
  /// reported by the export, not stored.
  std::vector<std::string> unoffered;

  nlohmann::ordered_json toJson() const;
  /// InputError naming `where` and the key for a malformed document.
  static FmuDescription fromJson(const nlohmann::ordered_json& j, const std::string& where);
  /// modelDescription.xml (FMI 2.0 Co-Simulation).
  std::string modelDescriptionXml() const;
};

struct ExportOptions {
  std::vector<std::string> inputs;     ///< see the file comment (empty: none; the experiment drives itself)
  std::vector<std::string> outputs;    ///< signal names with or without unit (empty: all)
  std::vector<std::string> overrides;  ///< "key.path=value" applied to the experiment before export (as --set)
  /// Folder with the FMU binary jointsim_fmu.so and the libraries it carries (empty: defaultBinaryDir()).
  std::string binary_dir;
  double step_size = 1e-3;  ///< DefaultExperiment stepSize [s]
};

/// The variables of a loaded experiment (types `tracking` and `joint_rig`; InputError for others, for an unknown
/// port or joint, or an unknown output).
FmuDescription describe(experiments::Experiment& experiment, const ExportOptions& options,
                        const std::string& model_identifier);

/// Writes the FMU `fmu_path` (its model identifier: the file name without .fmu, which must be a C identifier)
/// for the experiment file `config`. Written to a temporary name and renamed into place. InputError for bad
/// input (nothing written); Error when the FMU binary is missing.
FmuDescription exportFmu(const std::string& config, const std::string& fmu_path, const ExportOptions& options);

/// The FMU binary's folder: $JOINTSIM_FMU_BINARY_DIR, else `fmu/linux64` beside the running executable (the build
/// tree), else `../<libdir>/jointsim/fmu/linux64` from it (an installation), else the build folder of this library.
std::string defaultBinaryDir();

/// FMI 2.0 status values (fmi2OK ... fmi2Pending).
enum class Status { OK = 0, Warning = 1, Discard = 2, Error = 3, Fatal = 4 };

/// Messages to the importer: status, category ("logError", "logWarning", "logInfo") and text.
using Logger = std::function<void(Status, const char* category, const std::string& message)>;

/// The FMI 2.0 Co-Simulation semantics of one FMU instance, in C++ (the C functions of the binary forward here).
/// Every method returns a Status and logs the reason of any error; none throws.
class Instance {
 public:
  /// Reads `resource_dir`/jointsim_fmu.json and checks `guid`. Throws InputError (the C layer returns NULL).
  Instance(std::string instance_name, const std::string& resource_dir, const std::string& guid, Logger logger);
  ~Instance();
  Instance(const Instance&) = delete;
  Instance& operator=(const Instance&) = delete;

  const FmuDescription& description() const;
  Status setupExperiment(bool tolerance_defined, double tolerance, double start_time, bool stop_defined,
                         double stop_time);
  Status enterInitializationMode();
  Status exitInitializationMode();
  Status terminate();
  Status reset();
  Status getReal(const unsigned* vr, size_t n, double* values);
  Status setReal(const unsigned* vr, size_t n, const double* values);
  Status doStep(double current_communication_point, double step_size);
  /// Simulated time [s] (fmi2LastSuccessfulTime).
  double time() const;

  /// An FMU state (fmi2GetFMUstate and the functions after it): the complete state of the instance (its phase,
  /// the values of its inputs and parameters, the loaded experiment and the simulator's snapshot), or the bytes of a
  /// deserialised one. Opaque to the importer.
  struct State;
  /// fmi2GetFMUstate: `*state` null: a new state; else the state `*state` (from this instance) is overwritten.
  /// Allowed once the experiment is loaded (initialization mode, step complete).
  Status getState(State** state);
  /// fmi2SetFMUstate: back to `state` (of this FMU: checked); the run continues bit for bit as it did from there.
  Status setState(const State* state);
  /// fmi2FreeFMUstate.
  static void freeState(State* state);
  /// fmi2SerializedFMUstateSize, fmi2SerializeFMUstate (into `size` bytes), fmi2DeSerializeFMUstate (a new state
  /// from bytes of this FMU's serialisation; the snapshot in it is checked by setState against the plant).
  Status serializedSize(const State* state, size_t* size);
  Status serialize(const State* state, char* bytes, size_t size);
  Status deserialize(const char* bytes, size_t size, State** state);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace jointsim::fmi
