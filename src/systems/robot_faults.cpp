// RobotSystem (robot_system.hpp): faults during a run (faults.hpp): schedules, rebuilt drives, faulty sensors.
#include "jointsim/systems/robot_system.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <locale>
#include <random>
#include <sstream>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "jointsim/common/bytes.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/multibody/algorithms.hpp"

#include "systems/robot_system_internal.hpp"

namespace jointsim::systems {

using detail::controllerDriven;
using detail::entryOf;
using detail::quantise;

void RobotSystem::setFaults(std::vector<Fault> faults) {
  checkConfigurable("setFaults");
  std::vector<int> drive;
  for (const Fault& f : faults) {
    const int k = model_.jointIndex(f.joint);  // InputError for an unknown joint
    DriveSpec probe = drives_[static_cast<size_t>(k)];
    applyFault(probe, f);  // applies to this drive? (InputError naming the fault and the component)
    drive.push_back(k);
  }
  faults_ = std::move(faults);
  fault_drive_ = std::move(drive);
}

void RobotSystem::updateFaults(State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y, bool restart) const {
  if (faults_.empty()) return;
  std::vector<char> dirty(drives_.size(), restart ? 1 : 0);
  for (size_t i = 0; i < faults_.size(); ++i) {
    const Fault& f = faults_[i];
    const int k = fault_drive_[i];
    if (f.intermittent()) {
      long episode = -1;
      if (restart) st.stuck_episode[i] = -1;
      if (f.type == FaultType::SensorStuck && faultEpisode(f, t, &episode) && episode != st.stuck_episode[i]) {
        st.stuck_episode[i] = episode;  // the reading at the episode's start, held through it
        st.stuck_value[i] = y[k] + st.drives[static_cast<size_t>(k)].sensors.joint_bias;
      }
      continue;
    }
    const double v = t >= f.onset ? scheduledFaultValue(f, t) : std::numeric_limits<double>::quiet_NaN();
    const double before = st.fault_applied[i];
    st.fault_applied[i] = f.type == FaultType::BearingRipple ? (std::isnan(v) ? 0.0 : v) : v;
    if (f.parameterFault() && !(v == before || (std::isnan(v) && std::isnan(before))))
      dirty[static_cast<size_t>(k)] = 1;
  }
  rebuildDrives(st, dirty);
}

void RobotSystem::rebuildDrives(State& st, const std::vector<char>& dirty) const {
  for (size_t k = 0; k < drives_.size(); ++k) {
    if (!dirty.empty() && !dirty[k]) continue;
    DriveSpec d = drives_[k];
    for (size_t i = 0; i < faults_.size(); ++i)
      if (static_cast<size_t>(fault_drive_[i]) == k && faults_[i].parameterFault() && !std::isnan(st.fault_applied[i]))
        applyFault(d, faults_[i], st.fault_applied[i]);
    st.drives[k] = std::move(d);
    st.motors[k] = drive::DcMotor(st.drives[k].motor);
  }
}

double RobotSystem::faultySensor(const State& st, int k, double t, double q_meas) const {
  for (size_t i = 0; i < faults_.size(); ++i) {
    if (fault_drive_[i] != k || !faults_[i].intermittent() || !faultEpisode(faults_[i], t)) continue;
    switch (faults_[i].type) {
      case FaultType::SensorDropout: q_meas = 0.0; break;
      case FaultType::SensorStuck: q_meas = st.stuck_value[i]; break;
      case FaultType::SensorSpike: q_meas += faults_[i].value; break;
      default: break;
    }
  }
  return q_meas;
}

}  // namespace jointsim::systems
