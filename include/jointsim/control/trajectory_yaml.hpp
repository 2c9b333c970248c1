#pragma once
/// \file
/// Builds a joint trajectory from a YAML mapping (the value of an experiment's `trajectory:` key). SI units
/// only (no degrees).
///
///   type: point_to_point
///   start: [q_1, ..., q_n]                 # [rad], n = dof
///   segments:                              # at least one
///     - target: [..]                       # [rad] (n), required
///       velocity: 1.05                     # max joint speed [rad/s] } required together, unless
///       acceleration: 1.4                  # max joint accel [rad/s²] } `duration` is given
///       duration: 2.0                      # [s] optional: move time (then no velocity; acceleration optional)
///       dwell: 0.2                         # rest at the target [s], default 0
///
///   type: fourier
///   base_frequency: 0.1                    # f_base [Hz], required
///   harmonics: 5                           # N, optional (checked against the rows of a and b)
///   offset: [..]                           # q0 [rad] (n), required
///   a: [[a_11 .. a_1N], ..., [a_n1 .. a_nN]]   # [rad/s] (n rows of N), required
///   b: [[..], ...]                         # [rad/s] (same shape as a), required
///   fade_in: 1.0                           # quintic fade-in [s], default 1
///   duration: 11.0                         # [s], default fade_in + 1/base_frequency
///
///   type: csv
///   file: logs/ur5_run.csv                 # relative to base_dir (the experiment file's directory)
///   columns: [q1, q2, q3, q4, q5, q6]      # optional: joint columns by header name (n), else all columns
///   gap_factor: 3                          # a step > gap_factor × median step is an error; 0 disables
///
/// Every error is an InputError "FILE:LINE: KEY.PATH: message" (CSV errors also name the CSV and its row).

#include <memory>
#include <string>

#include "jointsim/control/trajectory.hpp"
#include "jointsim/io/yaml.hpp"

namespace jointsim::control {

/// Trajectory described by `node` (a mapping with a `type` key) for a robot with `dof` joints; CSV
/// files are resolved relative to `base_dir`.
/// \throws InputError with file:line: key.path on any missing, unknown, mis-sized or invalid key.
std::unique_ptr<JointTrajectory> trajectoryFromYaml(const io::YamlValue& node, int dof, const std::string& base_dir);

}  // namespace jointsim::control
