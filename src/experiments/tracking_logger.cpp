#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "experiments/tracking_internal.hpp"
#include "jointsim/multibody/algorithms.hpp"

namespace jointsim::experiments::detail {

TrackingLogger::TrackingLogger(const sim::RobotSystem& sys)
    : sys_(sys), id_model_(sys.model()), data_(id_model_), tip_(sys.model().frameIndex(sys.model().tip_frame)) {
  const int n = sys.dof();
  // Rotor inertias of all drives (rigid ones are already in the system's armature).
  for (int k = 0; k < n; ++k) {
    const auto& L = sys.layout(k);
    if (!L.rigid) id_model_.armature[k] += L.ratio * L.ratio * sys.drives()[static_cast<size_t>(k)].motor.J_M;
  }
  columns_.emplace_back("time[s]");
  const char* per_joint[][2] = {{"q_set", "rad"},          {"q", "rad"},           {"q_fb", "rad"},
                                {"qd", "rad/s"},           {"motor_velocity", "rad/s"}, {"current", "A"},
                                {"current_ref", "A"},      {"voltage", "V"},       {"gear_torque", "N·m"},
                                {"friction_torque", "N·m"}, {"id_torque", "N·m"}};
  for (const auto& name : sys.model().joint_names)
    for (const auto& c : per_joint) columns_.push_back(std::string(c[0]) + "_" + name + "[" + c[1] + "]");
  for (const char* c : {"tcp_x[m]", "tcp_y[m]", "tcp_z[m]", "tcp_roll[rad]", "tcp_pitch[rad]", "tcp_yaw[rad]"})
    columns_.emplace_back(c);
  row_.setZero(static_cast<Eigen::Index>(columns_.size()));
}

const Eigen::VectorXd& TrackingLogger::row(double t, const Eigen::Ref<const Eigen::VectorXd>& y) {
  const int n = sys_.dof();
  const sim::RobotSignals& s = sys_.signals(t, y);
  const Eigen::VectorXd& id = multibody::rnea(id_model_, data_, s.q_set, s.qd_set, s.qdd_set);
  Eigen::Index c = 0;
  row_[c++] = t;
  for (int k = 0; k < n; ++k) {
    const auto& d = sys_.drives()[static_cast<size_t>(k)];
    const double f_ss = d.friction ? d.friction->steadyState(s.qd_set[k]) : 0.0;
    row_[c++] = s.q_set[k];
    row_[c++] = y[k];
    row_[c++] = s.q_fb[k];
    row_[c++] = y[n + k];
    row_[c++] = s.qdm[k];
    row_[c++] = s.current[k];
    row_[c++] = s.i_ref[k];
    row_[c++] = s.voltage[k];
    row_[c++] = s.tau_gear[k];
    row_[c++] = s.tau_friction[k];
    row_[c++] = id[k] + f_ss;
  }
  multibody::forwardKinematics(id_model_, data_, y.head(n));
  const multibody::Placement& X = data_.oMf[static_cast<size_t>(tip_)];
  // Roll-pitch-yaw (URDF convention R = Rz(yaw) Ry(pitch) Rx(roll)).
  const double pitch = std::asin(std::clamp(-X.R(2, 0), -1.0, 1.0));
  const double roll = std::atan2(X.R(2, 1), X.R(2, 2));
  const double yaw = std::atan2(X.R(1, 0), X.R(0, 0));
  row_.segment(c, 3) = X.p;
  c += 3;
  row_[c++] = roll;
  row_[c++] = pitch;
  row_[c++] = yaw;
  return row_;
}

}  // namespace jointsim::experiments::detail
