#pragma once
// Internal: the tracking experiment's logger and runner entry.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "io/yaml_reader.hpp"
#include "jointsim/experiments/runner.hpp"
#include "jointsim/multibody/data.hpp"
#include "jointsim/sim/robot_system.hpp"

namespace jointsim::experiments::detail {

/// Builds one log row per sample: per joint q_set, q, q_fb, qd, motor velocity, current and its
/// reference, voltage, gear output torque, friction torque and the inverse-dynamics reference
/// id_torque = RNEA(q_set, q̇_set, q̈_set) + N² J_M q̈_set + friction steady state at q̇_set (the classic
/// rigid model, 002 Fig. 9); then the TCP position [m] and roll-pitch-yaw [rad] of the tip frame.
class TrackingLogger {
 public:
  explicit TrackingLogger(const sim::RobotSystem& sys);
  const std::vector<std::string>& columns() const { return columns_; }
  const Eigen::VectorXd& row(double t, const Eigen::Ref<const Eigen::VectorXd>& y);

 private:
  const sim::RobotSystem& sys_;
  multibody::Model id_model_;  // rotor inertias of every drive as armature
  multibody::Data data_;
  std::vector<std::string> columns_;
  Eigen::VectorXd row_;
  int tip_;
};

RunReport runDriveChain(const io::YamlValue& root, const std::string& config_path, const std::string& name,
                        const RunOptions& options);

RunReport runRobotR3Axis(const io::YamlValue& root, const std::string& config_path, const std::string& name,
                         const RunOptions& options);

RunReport runRobotR3Full(const io::YamlValue& root, const std::string& config_path, const std::string& name,
                         const RunOptions& options);

RunReport runClamping(const io::YamlValue& root, const std::string& config_path, const std::string& name,
                      const RunOptions& options);

RunReport runTracking(const io::YamlValue& root, const std::string& config_path, const std::string& name,
                      const RunOptions& options);

}  // namespace jointsim::experiments::detail
