#pragma once
/// \file
/// Readers of the blocks every experiment file shares (solver, duration and log rate, input profiles) and
/// their summary form; for the built-in experiment types and for a user's own (registry.hpp).

#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "jointsim/control/profile.hpp"
#include "jointsim/io/yaml.hpp"
#include "jointsim/sim/cvode_integrator.hpp"
#include "jointsim/sim/plant.hpp"
#include "jointsim/systems/joint_limits.hpp"

namespace jointsim::experiments {

/// `solver: {method: bdf|adams, rtol, atol, max_step, max_order, stability_limit_detection, max_num_steps}`;
/// absent keys keep `defaults`.
sim::CvodeOptions readSolver(const io::YamlValue& node, sim::CvodeOptions defaults);
/// Required `duration` [s] > 0 and optional `log_rate` [Hz] > 0 (log_rate keeps its value when absent).
void readDurationAndLogRate(const io::YamlValue& root, double& duration, double& log_rate);
/// `{type: constant|step|ramp|triangle|sine|piecewise|csv, ...}`; csv files are relative to the YAML file.
control::Profile readProfile(const io::YamlValue& node, const std::string& unit);
/// `joint_limits: ignore|warn|stop` or `joint_limits: {mode, stiffness [N·m/rad], damping [N·m·s/rad]}`
/// (systems/joint_limits.hpp); absent: warn.
systems::JointLimitSettings readJointLimits(const io::YamlValue& node);
/// The monitor of joint_limits for a plant whose signals include q_<joint> (time first in a row).
systems::JointLimitMonitor jointLimitMonitor(const multibody::Model& model, const sim::Plant& plant,
                                             const systems::JointLimitSettings& settings);
/// The solver options as written in summaries.
void solverJson(nlohmann::ordered_json& out, const sim::CvodeOptions& options);
/// The solver statistics as written in summaries.
void solverStatsJson(nlohmann::ordered_json& out, const sim::SolverStats& stats);

}  // namespace jointsim::experiments
