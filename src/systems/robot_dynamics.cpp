// RobotSystem (robot_system.hpp): the right-hand side stage by stage, its structured Jacobian, sampled control
// (measurement, control steps) and the logged signals.
#include "jointsim/systems/robot_system.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
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

RobotSystem::MotionMeasurement RobotSystem::measureMotion(State& st, int k, double t,
                                                          const Eigen::Ref<const Eigen::VectorXd>& y, double phi,
                                                          double phid, double Ts) const {
  const DriveLayout& L = layout_[static_cast<size_t>(k)];
  const SensorSpec& S = st.drives[static_cast<size_t>(k)].sensors;
  const double qm = L.rigid ? L.ratio * phi : y[L.motor];
  const double qdm = L.rigid ? L.ratio * phid : y[L.motor + 1];
  // Noise first, then the sensor's quantiser; encoder speed by differencing over Ts.
  MotionMeasurement m;
  m.q = faultySensor(st, k, t, quantise(y[k] + S.joint_bias + st.gauss(S.joint_noise), S.joint_quantum));
  m.qm = quantise(qm, S.motor_quantum);
  m.qdm = qdm;
  if (S.motor_quantum > 0.0) m.qdm = st.first_sample ? 0.0 : (m.qm - st.prev_qm_meas[k]) / Ts;
  m.qdm += st.gauss(S.motor_velocity_noise);
  st.prev_qm_meas[k] = m.qm;
  st.held_q_fb[k] = m.q;
  return m;
}

double RobotSystem::measureCurrent(State& st, int k, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const DriveLayout& L = layout_[static_cast<size_t>(k)];
  const SensorSpec& S = st.drives[static_cast<size_t>(k)].sensors;
  return quantise((L.current >= 0 ? y[L.current] : 0.0) + st.gauss(S.current_noise), S.current_quantum);
}

void RobotSystem::controlStep(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  State& st = own<State>(state);
  if (!sampled()) throw InputError("controlStep: sampled control is not enabled");
  if (current_rate_ > 0.0) {
    multiRateStep(st, t, y);
    return;
  }
  const int n = model_.nq;
  const double Ts = 1.0 / sample_rate_;
  setpointStage(st, t);
  const Eigen::VectorXd phi = coupled_ ? Eigen::VectorXd(Ginv_ * y.head(n)) : Eigen::VectorXd(y.head(n));
  const Eigen::VectorXd phid = coupled_ ? Eigen::VectorXd(Ginv_ * y.segment(n, n)) : Eigen::VectorXd(y.segment(n, n));
  std::vector<double> xdot(4, 0.0);
  for (int k = 0; k < n; ++k) {
    const DriveSpec& d = st.drives[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    const MotionMeasurement m = measureMotion(st, k, t, y, phi[k], phid[k], Ts);
    const double i_meas = measureCurrent(st, k, y);
    const CommandPort port = st.port[static_cast<size_t>(k)];
    if (!controllerDriven(port)) continue;  // voltage or torque command: the controller holds its state
    control::ControllerInputs in{st.sig.q_set[k], st.sig.qd_set[k], m.q,     m.qm,
                                 m.qdm,           i_meas,           L.ratio, d.motor.V_supply};
    in.entry = entryOf(port);
    in.command = st.cmd[k];
    double* x = L.controller >= 0 ? st.ctrl_x.data() + L.controller : nullptr;
    const control::ControllerOutputs out = controllers_[static_cast<size_t>(k)].evaluate(in, x, xdot.data());
    for (int j = 0; j < L.n_controller; ++j) x[j] += Ts * xdot[static_cast<size_t>(j)];  // forward Euler
    st.held_u[k] = out.u;
    st.held_i_ref[k] = out.i_ref;
  }
  st.first_sample = false;
}

void RobotSystem::multiRateStep(State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  // Every call is a current-loop sample; every inner_per_outer_-th also an outer (position, velocity) sample.
  const int n = model_.nq;
  const double Ts_in = 1.0 / current_rate_, Ts_out = 1.0 / sample_rate_;
  const bool outer = st.inner_count % inner_per_outer_ == 0;
  ++st.inner_count;
  setpointStage(st, t);
  double xdot[4] = {0.0, 0.0, 0.0, 0.0};
  for (int k = 0; k < n; ++k) {
    const DriveSpec& d = st.drives[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    const CommandPort port = st.port[static_cast<size_t>(k)];
    const bool cascade = d.controller.type == control::ControllerType::VoltageCascade;
    double* x = L.controller >= 0 ? st.ctrl_x.data() + L.controller : nullptr;
    const double i_meas = measureCurrent(st, k, y);
    if (outer) {  // measure the joint and the motor, advance the outer loops over Ts_out
      const double phi = coupled_ ? Ginv_.row(k).dot(y.head(n)) : y[k];
      const double phid = coupled_ ? Ginv_.row(k).dot(y.segment(n, n)) : y[n + k];
      const MotionMeasurement m = measureMotion(st, k, t, y, phi, phid, Ts_out);
      if (controllerDriven(port)) {
        control::ControllerInputs in{st.sig.q_set[k], st.sig.qd_set[k], m.q,     m.qm,
                                     m.qdm,           i_meas,           L.ratio, d.motor.V_supply};
        in.entry = entryOf(port);
        in.command = st.cmd[k];
        const control::ControllerOutputs out = controllers_[static_cast<size_t>(k)].evaluate(in, x, xdot);
        if (cascade) {
          x[0] += Ts_out * xdot[0];  // the velocity integrator; the current loop below
          st.held_i_ref[k] = out.i_ref;
        } else {
          for (int j = 0; j < L.n_controller; ++j) x[j] += Ts_out * xdot[j];
          st.held_u[k] = out.u;
          st.held_i_ref[k] = out.i_ref;
        }
      }
    }
    if (!cascade || !controllerDriven(port)) continue;
    // The current loop on the held reference (or the Current port's command), over Ts_in.
    control::ControllerInputs in{st.sig.q_set[k], st.sig.qd_set[k], st.held_q_fb[k], 0.0, 0.0,
                                 i_meas,          L.ratio,          d.motor.V_supply};
    in.entry = control::ControlEntry::Current;
    in.command = port == CommandPort::Current ? st.cmd[k] : st.held_i_ref[k];
    const control::ControllerOutputs out = controllers_[static_cast<size_t>(k)].evaluate(in, x, xdot);
    x[1] += Ts_in * xdot[1];
    st.held_u[k] = out.u;
  }
  st.first_sample = false;
}

void RobotSystem::setpointStage(const State& st, double t, bool anchored) const {
  if (setpoints_) {
    setpoints_(t, st.sig.q_set, st.sig.qd_set, st.sig.qdd_set);
    if (relative_ && anchored) st.sig.q_set += st.anchor;  // relative replay (setRelativeReplay)
  } else {                                                 // no reference given: hold the start pose
    st.sig.q_set = st.q_start;
    st.sig.qd_set.setZero();
    st.sig.qdd_set.setZero();
  }
  for (int k = 0; k < model_.nq; ++k)
    if (st.ref_held[static_cast<size_t>(k)]) {
      st.sig.q_set[k] = st.ref_q[k];
      st.sig.qd_set[k] = st.ref_qd[k];
      st.sig.qdd_set[k] = st.ref_qdd[k];
    }
}

void RobotSystem::measurementStage(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const int n = model_.nq;
  const auto q = y.head(n);
  const auto qd = y.segment(n, n);
  // Gear output angles and speeds: φ = G⁻¹ q.
  if (coupled_) {
    st.phi.noalias() = Ginv_ * q;
    st.phid.noalias() = Ginv_ * qd;
  } else {
    st.phi = q;
    st.phid = qd;
  }
  for (int k = 0; k < n; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    st.sig.qm[k] = L.rigid ? L.ratio * st.phi[k] : y[L.motor];
    st.sig.qdm[k] = L.rigid ? L.ratio * st.phid[k] : y[L.motor + 1];
    st.sig.current[k] = L.current >= 0 ? y[L.current] : 0.0;
    st.sig.q_fb[k] = sampled() ? st.held_q_fb[k]
                               : faultySensor(st, k, t, q[k] + st.drives[static_cast<size_t>(k)].sensors.joint_bias);
  }
}

void RobotSystem::controllerStage(const State& st, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const {
  for (int k = 0; k < model_.nq; ++k) {
    const DriveSpec& d = st.drives[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    control::ControllerOutputs out;
    const CommandPort port = st.port[static_cast<size_t>(k)];
    if (!controllerDriven(port)) {  // the command bypasses the controller, whose integrators hold
      out.voltage = port == CommandPort::Voltage;
      out.u = st.cmd[k];
      if (!sampled())
        for (int j = 0; j < L.n_controller; ++j) ydot[L.controller + j] = 0.0;
    } else if (sampled()) {  // zero-order hold of the last sample's outputs
      out.voltage = d.controller.type == control::ControllerType::VoltageCascade;
      out.u = st.held_u[k];
      out.i_ref = st.held_i_ref[k];
    } else {
      control::ControllerInputs in{st.sig.q_set[k], st.sig.qd_set[k],  st.sig.q_fb[k], st.sig.qm[k],
                                   st.sig.qdm[k],   st.sig.current[k], L.ratio,        d.motor.V_supply};
      in.entry = entryOf(port);
      in.command = st.cmd[k];
      out = controllers_[static_cast<size_t>(k)].evaluate(in, L.controller >= 0 ? y.data() + L.controller : nullptr,
                                                          L.controller >= 0 ? ydot + L.controller : nullptr);
    }
    st.sig.i_ref[k] = out.i_ref;
    st.sig.u[k] = out.u;
    st.out_is_voltage[static_cast<size_t>(k)] = out.voltage;
  }
}

void RobotSystem::powerElectronicsStage(const State& st) const {
  // Averaged PWM: the commanded voltage, saturated at the supply [Raviola2023, eq. 1].
  for (int k = 0; k < model_.nq; ++k) {
    const bool electrics = layout_[static_cast<size_t>(k)].current >= 0;
    const double V_cmd = st.out_is_voltage[static_cast<size_t>(k)] ? st.sig.u[k] : 0.0;
    st.sig.voltage[k] = electrics ? st.motors[static_cast<size_t>(k)].supplyVoltage(V_cmd) : 0.0;
  }
}

void RobotSystem::motorElectricsStage(const State& st, double* ydot) const {
  // L di/dt = V − R i − k_e q̇_m, τ_M = k_t i; a motor without electrics gives the commanded torque.
  for (int k = 0; k < model_.nq; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    const drive::DcMotor& motor = st.motors[static_cast<size_t>(k)];
    if (L.current >= 0 && st.port[static_cast<size_t>(k)] == CommandPort::MotorTorque) {
      // Electrics bypassed: the torque is the command; the current relaxes to τ/k_t with L/R.
      const drive::DcMotorParams& m = st.drives[static_cast<size_t>(k)].motor;
      st.sig.tau_motor[k] = st.sig.u[k];
      ydot[L.current] = (st.sig.u[k] / m.kt - st.sig.current[k]) * m.R / m.L;
    } else if (L.current >= 0) {
      const double V_cmd = st.out_is_voltage[static_cast<size_t>(k)] ? st.sig.u[k] : 0.0;
      ydot[L.current] = motor.currentDerivative(st.sig.current[k], V_cmd, st.sig.qdm[k]);
      st.sig.tau_motor[k] = motor.torque(st.sig.current[k]);
    } else {
      st.sig.tau_motor[k] = st.out_is_voltage[static_cast<size_t>(k)] ? 0.0 : st.sig.u[k];
    }
  }
}

void RobotSystem::transmissionStage(const State& st, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const {
  for (int k = 0; k < model_.nq; ++k) {
    const DriveSpec& d = st.drives[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    if (L.rigid) {
      st.sig.tau_gear[k] = L.ratio * st.sig.tau_motor[k];  // the rotor's inertial reaction follows the accelerations
      continue;
    }
    const drive::PortTorques pt =
        d.transmission->evaluate({st.sig.qm[k], st.sig.qdm[k], st.phi[k], st.phid[k]},
                                 L.gear >= 0 ? y.data() + L.gear : nullptr, L.gear >= 0 ? ydot + L.gear : nullptr);
    st.sig.tau_gear[k] = pt.tau_out;
    ydot[L.motor] = st.sig.qdm[k];
    ydot[L.motor + 1] = (st.sig.tau_motor[k] - pt.tau_in) / d.motor.J_M;  // rotor: J_M q̈_m = τ_M − τ_in
  }
}

void RobotSystem::frictionStage(const State& st, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot) const {
  // On the gear output shaft, driven by the gear output torque.
  // A model that reads only v and at most one state is memoised per drive (State::FrictionMemo): the same bits in, the
  // same bits out, as evaluate() is pure.
  auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; };
  for (int k = 0; k < model_.nq; ++k) {
    const DriveSpec& d = st.drives[static_cast<size_t>(k)];
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    if (!d.friction) {
      st.sig.tau_friction[k] = 0.0;
      continue;
    }
    const double* z = L.friction >= 0 ? y.data() + L.friction : nullptr;
    double* zdot = L.friction >= 0 ? ydot + L.friction : nullptr;
    const double v = st.phid[k], z0 = L.n_friction == 1 ? z[0] : 0.0;
    const bool memoised = L.n_friction <= 1 && !d.friction->readsDrivingTorque();
    State::FrictionMemo& m = st.friction_memo[static_cast<size_t>(k)];
    if (memoised && m.model == d.friction && same(m.v, v) && same(m.z, z0)) {
      st.sig.tau_friction[k] = m.tau;
      if (zdot) zdot[0] = m.zdot;
      continue;
    }
    st.sig.tau_friction[k] = d.friction->evaluate({v, st.sig.tau_gear[k]}, z, zdot);
    if (memoised) {
      if (m.model != d.friction) m.model = d.friction;
      m.v = v;
      m.z = z0;
      m.tau = st.sig.tau_friction[k];
      m.zdot = zdot ? zdot[0] : 0.0;
    }
  }
  // A bearing defect of the output shaft: τ_b = A sin(order · φ_out), with the amplitude of its schedule.
  for (size_t i = 0; i < faults_.size(); ++i)
    if (faults_[i].type == FaultType::BearingRipple) {
      const int k = fault_drive_[i];
      st.sig.tau_friction[k] += st.fault_applied[i] * std::sin(faults_[i].order * st.phi[k]);
    }
}

void RobotSystem::jointTorqueStage(const State& st) const {
  // τ_out = τ_gear − τ_f on the gear outputs; τ_joint = G⁻ᵀ τ_out.
  st.tau_out = st.sig.tau_gear - st.sig.tau_friction;
  if (coupled_)
    st.tau.noalias() = Ginv_.transpose() * st.tau_out;
  else
    st.tau = st.tau_out;
  st.sig.tau_joint = st.tau;
}

void RobotSystem::jointLoadStage(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const int n = model_.nq;
  if (stops_.active()) {  // end stops act on the joints beside the drives
    stops_.torques(y.head(n), y.segment(n, n), st.sig.tau_stop);
    st.tau += st.sig.tau_stop;
  }
  for (int k = 0; k < n; ++k)  // external load torques at the joints (the J.load_torque inputs)
    if (load_profiles_.active(st.loads, static_cast<size_t>(k)))
      st.tau[k] += load_profiles_.value(st.loads, static_cast<size_t>(k), t);
}

void RobotSystem::multibodyStage(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const int n = model_.nq;
  const auto q = y.head(n);
  const auto qd = y.segment(n, n);
  const multibody::Matrix6Xd* fext = nullptr;
  if (wrenches_ || !st.user_wrenches.empty()) {
    multibody::forwardKinematics(model_, st.data, q);
    st.fext.setZero();
    if (wrenches_) wrenches_(t, model_, st.data, q, qd, st.fext);
    for (const auto& [f, w] : st.user_wrenches) {
      // World wrench at the frame origin → body frame of the carrying body, moment about the body origin.
      const multibody::Frame& fr = model_.frames[static_cast<size_t>(f)];
      const multibody::Placement& B = st.data.oMi[static_cast<size_t>(fr.joint)];
      const Eigen::Vector3d r = st.data.oMf[static_cast<size_t>(f)].p - B.p;
      st.fext.col(fr.joint).head<3>() += B.R.transpose() * (w.tail<3>() + r.cross(w.head<3>()));
      st.fext.col(fr.joint).tail<3>() += B.R.transpose() * w.head<3>();
    }
    fext = &st.fext;
  }
  if (crba_path_) {
    // (M + G⁻ᵀ diag(N² J_M) G⁻¹) q̈ = τ − h(q, q̇) [− Jᵀ f_ext through RNEA]
    if (fext)
      st.data.nle = multibody::rnea(model_, st.data, q, qd, st.zero, fext);
    else
      multibody::nonLinearEffects(model_, st.data, q, qd);
    st.M = multibody::crba(model_, st.data, q);
    st.M += reflected_;
    st.llt.compute(st.M);
    st.sig.qdd = st.tau - st.data.nle;
    st.llt.solveInPlace(st.sig.qdd);
  } else {
    st.sig.qdd = multibody::aba(model_, st.data, q, qd, st.tau, fext);
  }
}

void RobotSystem::rotorReactionStage(const State& st) const {
  // Rigid drives: the gear output torque includes the rotor's inertial reaction −N² J_M φ̈.
  for (int k = 0; k < model_.nq; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    if (!L.rigid) continue;
    const double phidd = coupled_ ? Ginv_.row(k).dot(st.sig.qdd) : st.sig.qdd[k];
    st.sig.tau_gear[k] -= L.ratio * L.ratio * st.drives[static_cast<size_t>(k)].motor.J_M * phidd;
  }
}

void RobotSystem::evaluate(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y, double* ydot,
                           Pass pass) const {
  // Under sampled control the right-hand side reads the held controller outputs, not the reference.
  if (pass == Pass::Signals || !sampled()) setpointStage(st, t);
  measurementStage(st, t, y);
  controllerStage(st, y, ydot);
  powerElectronicsStage(st);
  motorElectricsStage(st, ydot);
  transmissionStage(st, y, ydot);
  frictionStage(st, y, ydot);
  jointTorqueStage(st);
  jointLoadStage(st, t, y);
  const int n = model_.nq;
  Eigen::Map<Eigen::VectorXd> yd(ydot, n_states_);
  yd.head(n) = y.segment(n, n);
  if (pass == Pass::DrivesOnly) return;  // (the Jacobian's drive-local evaluations: its q̈ rows left as they are)
  multibodyStage(st, t, y);
  rotorReactionStage(st);
  yd.segment(n, n) = st.sig.qdd;
}

void RobotSystem::derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                              Eigen::Ref<Eigen::VectorXd> ydot) const {
  evaluate(own<State>(state), t, y, ydot.data(), Pass::Derivatives);
}

sim::JacobianStructure RobotSystem::jacobianStructure() const { return jacobianStructure(nullptr); }

bool RobotSystem::timeInvariant(const sim::PlantState& state) const {
  // evaluate() reads t in the reference and the sensor faults' episodes (both only through a continuous controller: a
  // sampled one reads the held measurement and outputs, a voltage or motor-torque port bypasses it), the load-torque
  // profiles and the wrench function. (Parameter faults change at time events, between which they are constant.)
  const State& st = own<State>(state);
  if (wrenches_ || load_profiles_.dependsOnTime(st.loads)) return false;
  if (sampled()) return true;
  for (const CommandPort port : st.port)
    if (controllerDriven(port)) return false;
  return true;
}

std::vector<int> RobotSystem::oscillatoryStates() const {
  std::vector<int> states;
  for (int i = 0; i < model_.nq; ++i) states.push_back(i);
  for (const DriveLayout& L : layout_) {
    auto add = [&states](int first, int count) {
      if (first >= 0)
        for (int j = 0; j < count; ++j) states.push_back(first + j);
    };
    if (!L.rigid) add(L.motor, 2);
    add(L.current, 1);
    add(L.gear, L.n_gear);
  }
  return states;
}

sim::JacobianStructure RobotSystem::jacobianStructure(std::vector<int>* drive_of_block) const {
  sim::JacobianStructure s;
  const int n = model_.nq;
  for (int i = 0; i < 2 * n; ++i) s.hub.push_back(i);
  if (drive_of_block) drive_of_block->clear();
  for (int k = 0; k < n; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    std::vector<int> b;
    auto add = [&b](int first, int count) {
      if (first >= 0)
        for (int j = 0; j < count; ++j) b.push_back(first + j);
    };
    if (!L.rigid) add(L.motor, 2);
    add(L.current, 1);
    add(L.gear, L.n_gear);
    add(L.friction, L.n_friction);
    if (!sampled()) add(L.controller, L.n_controller);  // sampled: the controller states are not ODE states
    if (b.empty()) continue;
    s.blocks.push_back(std::move(b));
    if (drive_of_block) drive_of_block->push_back(k);
    if (!coupled_) {
      // Drive k reads its own joint's angle and rate only (φ = q without a coupling matrix; its controller and
      // sensors read joint k) and acts on the accelerations only (through τ_k and M⁻¹; q' = q̇ does not see it).
      s.block_hub_columns.push_back({k, n + k});
      s.block_hub_rows.emplace_back();
      for (int i = n; i < 2 * n; ++i) s.block_hub_rows.back().push_back(i);
    }
  }
  return s;
}

void RobotSystem::jacobian(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                           const Eigen::Ref<const Eigen::VectorXd>& f, const Eigen::Ref<const Eigen::VectorXd>& inc,
                           Eigen::Ref<Eigen::MatrixXd> J, sim::JacobianKind kind) const {
  const State& st = own<State>(state);
  const int n = model_.nq;
  Eigen::VectorXd& yp = st.jac_y;
  Eigen::VectorXd& fp = st.jac_f;
  yp = y;
  const bool with_fext = wrenches_ || !st.user_wrenches.empty();
  if (kind == sim::JacobianKind::Analytic && !coupled_ && !crba_path_ && !with_fext) {
    // The base point's drive output torques and joint torques; its q̈ is not needed (the ABA derivatives below bring
    // their own), so no multibody pass.
    evaluate(st, t, y, fp.data(), Pass::DrivesOnly);
    st.jac_tau0 = st.tau_out;
    jacobianByJoint(st, t, y, f, inc, J);
    return;
  }
  // The base point: the drives' output torques and the total joint torque (drives, end stops) behind q̈.
  evaluate(st, t, y, fp.data(), Pass::Derivatives);
  st.jac_tau0 = st.tau_out;
  st.jac_qdd0 = st.sig.qdd;
  const Eigen::VectorXd& tau_total = st.tau;
  // ∂q̈/∂τ_out = M⁻¹ G⁻ᵀ, column by column; q̈ is affine in the joint torque, so a unit difference is exact to
  // rounding. (The external wrenches st.fext of the base evaluation stay in place.)
  const auto q = y.head(n);
  const auto qd = y.segment(n, n);
  for (int j = 0; j < n; ++j) {
    st.jac_tau = tau_total;
    if (coupled_)
      st.jac_tau += Ginv_.row(j).transpose();
    else
      st.jac_tau[j] += 1.0;
    if (crba_path_) {
      st.jac_P.col(j) = st.jac_tau - st.data.nle;
      st.llt.solveInPlace(st.jac_P.col(j));
    } else {
      st.jac_P.col(j) = multibody::aba(model_, st.data, q, qd, st.jac_tau, with_fext ? &st.fext : nullptr);
    }
    st.jac_P.col(j) -= st.jac_qdd0;
  }
  // Hub columns: whole difference quotients.
  for (int j = 0; j < 2 * n; ++j) {
    yp[j] = y[j] + inc[j];
    evaluate(st, t, yp, fp.data(), Pass::Derivatives);
    J.col(j) = (fp - f) / inc[j];
    yp[j] = y[j];
  }
  driveColumns(st, t, y, f, inc, J);
}

void RobotSystem::driveColumns(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                               const Eigen::Ref<const Eigen::VectorXd>& f, const Eigen::Ref<const Eigen::VectorXd>& inc,
                               Eigen::Ref<Eigen::MatrixXd> J) const {
  // Drive columns: state c of every drive at once (a drive's states act on its own rows and, through its output
  // torque τ_out,k, on q̈ by the column k of ∂q̈/∂τ_out = st.jac_P).
  // A drive on a port that replaces its continuous controller (voltage, motor torque) holds the controller's states
  // (ẋ = 0) and reads none of them: their columns are exactly 0 and need no evaluation (they are its block's last
  // states; J is zero there on entry).
  const int n = model_.nq;
  Eigen::VectorXd& yp = st.jac_y;
  Eigen::VectorXd& fp = st.jac_f;
  const auto& blocks = st.jac_structure.blocks;
  size_t max_m = 0;
  for (size_t bi = 0; bi < blocks.size(); ++bi) {
    const int k = st.jac_block_drive[bi];
    size_t m = blocks[bi].size();
    if (!sampled() && !controllerDriven(st.port[static_cast<size_t>(k)]))
      m -= static_cast<size_t>(layout_[static_cast<size_t>(k)].n_controller);
    st.jac_block_columns[bi] = m;
    max_m = std::max(max_m, m);
  }
  for (size_t c = 0; c < max_m; ++c) {
    for (size_t bi = 0; bi < blocks.size(); ++bi)
      if (st.jac_block_columns[bi] > c) yp[blocks[bi][c]] = y[blocks[bi][c]] + inc[blocks[bi][c]];
    evaluate(st, t, yp, fp.data(), Pass::DrivesOnly);  // q̈'s rows come from τ_out through jac_P
    for (size_t bi = 0; bi < blocks.size(); ++bi) {
      const auto& b = blocks[bi];
      if (st.jac_block_columns[bi] <= c) continue;
      const int s = b[c];
      for (int r : b) J(r, s) = (fp[r] - f[r]) / inc[s];
      const int k = st.jac_block_drive[bi];
      J.col(s).segment(n, n) = st.jac_P.col(k) * ((st.tau_out[k] - st.jac_tau0[k]) / inc[s]);
      yp[s] = y[s];
    }
  }
}

void RobotSystem::jacobianByJoint(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                                  const Eigen::Ref<const Eigen::VectorXd>& f,
                                  const Eigen::Ref<const Eigen::VectorXd>& inc, Eigen::Ref<Eigen::MatrixXd> J) const {
  // Without a coupling matrix, external wrenches or the CRBA path, everything but the multibody depends on one joint
  // each: drive k's states, its output torque and joint k's end stop see only q_k and q̇_k (the controllers read their
  // own joint; the drives never read q̈). So the hub columns split into
  //   ∂q̈/∂q_j = (∂ABA/∂q)(:, j) + M⁻¹(:, j) ∂τ_j/∂q_j,   ∂q̈/∂q̇_j = (∂ABA/∂q̇)(:, j) + M⁻¹(:, j) ∂τ_j/∂q̇_j,
  // with the multibody's part from the analytic ABA derivatives [Carpentier2018] at the joint torques τ of the base
  // point, and the joint-local parts (∂τ_j and drive j's rows) from two evaluations that perturb every q_j (then
  // every q̇_j) at once. ∂q̈/∂τ_out = M⁻¹ too. O(n²) instead of the 2n + n evaluations O(n) each of the general path.
  const int n = model_.nq;
  Eigen::VectorXd& yp = st.jac_y;
  Eigen::VectorXd& fp = st.jac_f;
  st.jac_tau_base = st.tau;
  multibody::computeAbaDerivatives(model_, st.jac_data, y.head(n), y.segment(n, n), st.jac_tau_base);
  st.jac_P = st.jac_data.Minv;
  const auto& blocks = st.jac_structure.blocks;
  for (int part = 0; part < 2; ++part) {  // 0: the angles q, 1: the rates q̇
    const int off = part * n;
    for (int j = 0; j < n; ++j) yp[off + j] = y[off + j] + inc[off + j];
    evaluate(st, t, yp, fp.data(), Pass::DrivesOnly);  // the joint torques and the drives' rows only
    const Eigen::MatrixXd& dqdd = part == 0 ? st.jac_data.ddq_dq : st.jac_data.ddq_dqd;
    for (int j = 0; j < n; ++j) {
      const int s = off + j;
      if (part == 1) J(j, s) = 1.0;  // q' = q̇
      J.col(s).segment(n, n) = dqdd.col(j) + st.jac_P.col(j) * ((st.tau[j] - st.jac_tau_base[j]) / inc[s]);
      yp[s] = y[s];
    }
    for (size_t bi = 0; bi < blocks.size(); ++bi) {
      const int k = st.jac_block_drive[bi];
      const int s = off + k;
      for (int r : blocks[bi]) J(r, s) = (fp[r] - f[r]) / inc[s];
    }
  }
  driveColumns(st, t, y, f, inc, J);
}

const RobotSignals& RobotSystem::driveSignals(const sim::PlantState& state, double t,
                                              const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const State& st = own<State>(state);
  evaluate(st, t, y, st.tmp.data(), Pass::Signals);
  return st.sig;
}

void RobotSystem::signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                          Eigen::Ref<Eigen::VectorXd> out) const {
  const State& st = own<State>(state);
  const int n = model_.nq;
  const RobotSignals& s = driveSignals(state, t, y);
  const Eigen::VectorXd& id = multibody::rnea(id_model_, st.id_data, s.q_set, s.qd_set, s.qdd_set);
  Eigen::Index c = 0;
  for (int k = 0; k < n; ++k) {
    const auto& d = st.drives[static_cast<size_t>(k)];
    const double f_ss = d.friction ? d.friction->steadyState(s.qd_set[k]) : 0.0;
    out[c++] = s.q_set[k];
    out[c++] = y[k];
    out[c++] = s.q_fb[k];
    out[c++] = y[n + k];
    out[c++] = s.qdm[k];
    out[c++] = s.current[k];
    out[c++] = s.i_ref[k];
    out[c++] = s.voltage[k];
    out[c++] = s.tau_gear[k];
    out[c++] = s.tau_friction[k];
    out[c++] = id[k] + f_ss;
  }
  multibody::forwardKinematics(id_model_, st.id_data, y.head(n));
  const multibody::Placement& X = st.id_data.oMf[static_cast<size_t>(tip_)];
  // Roll-pitch-yaw (URDF convention R = Rz(yaw) Ry(pitch) Rx(roll)).
  const double pitch = std::asin(std::clamp(-X.R(2, 0), -1.0, 1.0));
  const double roll = std::atan2(X.R(2, 1), X.R(2, 2));
  const double yaw = std::atan2(X.R(1, 0), X.R(0, 0));
  out.segment(c, 3) = X.p;
  c += 3;
  out[c++] = roll;
  out[c++] = pitch;
  out[c++] = yaw;
  for (int i : stops_.joints()) out[c++] = s.tau_stop[i];
}

double RobotSystem::mechanicalEnergy(const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const int n = model_.nq;
  const auto q = y.head(n);
  const auto qd = y.segment(n, n);
  multibody::Data data(model_);
  double E = multibody::kineticEnergy(model_, data, q, qd) + multibody::potentialEnergy(model_, data, q);
  if (crba_path_) E += 0.5 * qd.dot(reflected_ * qd);
  E += stops_.energy(q);
  const Eigen::VectorXd phi = Ginv_ * q, phid = Ginv_ * qd;
  for (int k = 0; k < n; ++k) {
    const DriveLayout& L = layout_[static_cast<size_t>(k)];
    if (L.rigid) continue;
    const double qdm = y[L.motor + 1];
    E += 0.5 * drives_[static_cast<size_t>(k)].motor.J_M * qdm * qdm;
    E += drives_[static_cast<size_t>(k)].transmission->storedEnergy({y[L.motor], qdm, phi[k], phid[k]},
                                                                    L.gear >= 0 ? y.data() + L.gear : nullptr);
  }
  return E;
}

}  // namespace jointsim::systems
