#pragma once
/// \file
/// The built-in experiment types (the rows of the registry, registry.hpp) and the public readers of their
/// setups from an experiment file's document (the whole file as `root`; formats in docs/experiments.md).
/// Each throws InputError naming the file, the line and the key path.

#include <memory>
#include <string>
#include <vector>

#include "jointsim/control/trajectory.hpp"
#include "jointsim/experiments/registry.hpp"
#include "jointsim/io/yaml.hpp"
#include "jointsim/systems/clamped_robot.hpp"
#include "jointsim/systems/drive_chain.hpp"
#include "jointsim/systems/joint_rig.hpp"
#include "jointsim/systems/passive_robot.hpp"
#include "jointsim/systems/robot_system.hpp"
#include "jointsim/systems/robotr3_axis.hpp"
#include "jointsim/systems/robotr3_full.hpp"

namespace jointsim::experiments {

// ------------------------------------------------------------------------------------------- registry rows
ExperimentType passiveRobotExperimentType();  ///< `passive_robot`
ExperimentType jointRigExperimentType();      ///< `joint_rig`
ExperimentType trackingExperimentType();      ///< `tracking`
ExperimentType driveChainExperimentType();    ///< `drive_chain`
ExperimentType robotR3AxisExperimentType();   ///< `robotr3_axis`
ExperimentType robotR3FullExperimentType();   ///< `robotr3_full`
ExperimentType clampingExperimentType();      ///< `clamping`

// ------------------------------------------------------------------------------------------- setup readers
/// `passive_robot`: the robot (loaded from `robot:`) and the run parameters.
struct PassiveRobotSetup {
  std::string robot_file;
  multibody::Model model;
  systems::PassiveRobotParams params;
};
PassiveRobotSetup readPassiveRobotSetup(const io::YamlValue& root, const std::string& name);
/// `joint_rig`.
systems::JointRigSetup readJointRigSetup(const io::YamlValue& root, const std::string& name);
/// `drive_chain`.
systems::DriveChainSetup readDriveChainSetup(const io::YamlValue& root, const std::string& name);
/// `robotr3_axis`.
systems::RobotR3AxisSetup readRobotR3AxisSetup(const io::YamlValue& root, const std::string& name);
/// `robotr3_full`.
systems::RobotR3FullSetup readRobotR3FullSetup(const io::YamlValue& root, const std::string& name);
/// `clamping`: the setup and whether identify-ready curves are written (`curves:`).
struct ClampingExperimentSetup {
  std::string robot_file;
  systems::ClampingSetup setup;
  bool curves = true;
};
ClampingExperimentSetup readClampingSetup(const io::YamlValue& root, const std::string& name);
/// `tracking`: the robot with drives (faults applied, sampled control set), its trajectory and run settings.
struct TrackingSetup {
  std::string robot_file;
  std::shared_ptr<systems::RobotSystem> robot;
  std::shared_ptr<const control::JointTrajectory> trajectory;
  double duration = 0.0;      ///< [s]
  double log_rate = 500.0;    ///< [Hz]
  double control_rate = 0.0;  ///< [Hz]; 0: continuous control
  sim::CvodeOptions solver;
  systems::JointLimitSettings joint_limits;  ///< also set on `robot` (end stops in mode stop)
};
TrackingSetup readTrackingSetup(const io::YamlValue& root, const std::string& name,
                                const std::vector<systems::Fault>& faults = {});

}  // namespace jointsim::experiments
