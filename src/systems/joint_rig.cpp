#include "jointsim/systems/joint_rig.hpp"

#include <algorithm>
#include <cmath>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/control/joint_controller.hpp"

namespace jointsim::systems {

sim::CvodeOptions JointRigSetup::defaultSolver() { return sim::stiffDriveSolver(1e-8, 1e-10); }

void JointRigSetup::validate() const {
  // Keys as in a joint_rig experiment file.
  const char* const c = "joint rig";
  check::that(transmission != nullptr, c, "transmission", "missing");
  check::that(!((input == RigInput::Voltage || (input == RigInput::VelocityPI && pi.voltage_output)) && !motor), c,
              "motor", "voltage input needs the motor electrics (motor parameters)");
  if (motor) {
    try {
      motor->validate();
    } catch (const InputError& e) {
      throw InputError::parameter(c, "motor." + e.keyPath(), e.message());
    }
  }
  if (!motor) check::positive(c, "rotor_inertia", rotor_inertia, "kg·m²");
  check::that(!(clamped && transmission->isRigid()), c, "load.clamped",
              "a rigid transmission with a clamped output locks the motor; use a compliant transmission");
  if (!clamped) check::positive(c, "load.inertia", load_inertia, "kg·m²");
  check::that(!(clamped && load_torque), c, "load.torque", "a clamped output takes no load torque");
  check::nonNegative(c, "load.damping", load_damping, "N·m·s/rad");
  check::that(!(friction && friction_side == Side::Output && clamped), c, "friction.side",
              "friction on the output side of a clamped output has no effect; use side: motor");
  if (input == RigInput::VelocityPI) {
    check::positive(c, "input.controller.limit", pi.limit, "(N·m or V)");
    check::that(!(pi.measure == Side::Output && clamped), c, "input.controller.measure",
                "the clamped output does not move");
  }
  check::positive(c, "duration", duration, "s");
  check::positive(c, "log_rate", log_rate, "Hz");
}

struct JointRig::Eval {
  double command = 0, tau_motor = 0, current = 0, voltage = 0, di = 0, de = 0;
  double tau_in = 0, tau_out = 0, tau_f = 0, tau_load = 0;
  double q_l = 0, qd_l = 0, qdd_m = 0, qdd_l = 0;
};

JointRig::JointRig(JointRigSetup setup) : s_(std::move(setup)) {
  s_.validate();
  if (s_.motor) motor_.emplace(*s_.motor);
  J_m_ = s_.motor ? s_.motor->J_M : s_.rotor_inertia;
  const bool electrics = s_.input == RigInput::Voltage || (s_.input == RigInput::VelocityPI && s_.pi.voltage_output);
  n_ = 2;
  if (electrics) i_idx_ = n_++;
  nx_ = s_.transmission->stateSize();
  if (nx_ > 0) {
    x_idx_ = n_;
    n_ += nx_;
  }
  nz_ = s_.friction ? s_.friction->stateSize() : 0;
  if (nz_ > 0) {
    z_idx_ = n_;
    n_ += nz_;
  }
  if (!s_.transmission->isRigid() && !s_.clamped) {
    l_idx_ = n_;
    n_ += 2;
  }
  if (s_.input == RigInput::VelocityPI) e_idx_ = n_++;
  if (nx_ > 64 || nz_ > 64) throw InputError("joint rig: component with more than 64 internal states");

  signals_ = {"motor_angle[rad]", "motor_velocity[rad/s]", "motor_torque[N·m]"};
  if (i_idx_ >= 0) {
    signals_.emplace_back("motor_current[A]");
    signals_.emplace_back("motor_voltage[V]");
  }
  switch (s_.input) {
    case RigInput::MotorTorque: signals_.emplace_back("command_torque[N·m]"); break;
    case RigInput::Voltage: signals_.emplace_back("command_voltage[V]"); break;
    case RigInput::VelocityPI: signals_.emplace_back("reference_velocity[rad/s]"); break;
  }
  if (s_.load_torque) signals_.emplace_back("load_torque[N·m]");
  for (const char* c : {"transmission_torque_in[N·m]", "transmission_torque_out[N·m]", "friction_torque[N·m]",
                        "output_angle[rad]", "output_velocity[rad/s]"})
    signals_.emplace_back(c);
  for (const auto& name : s_.transmission->stateNames()) signals_.push_back("gear_" + name);
  if (s_.friction)
    for (const auto& name : s_.friction->stateNames()) signals_.push_back("friction_" + name);
  if (e_idx_ >= 0) signals_.emplace_back("pi_integral[rad]");
}

void JointRig::State::save(ByteWriter& out) const {
  out.boolean(held);
  out.f64(command);
  out.f64(load_torque);
}

void JointRig::State::load(ByteReader& in) {
  held = in.boolean("held");
  command = in.f64("command");
  load_torque = in.f64("load torque");
  if (!std::isfinite(command) || !std::isfinite(load_torque)) in.fail("a command or load torque that is not finite");
  if (load_torque != 0.0 && static_cast<const JointRig&>(owner()).s_.clamped)
    in.fail("a load torque on a clamped output");
}

void JointRig::setCommand(sim::PlantState& state, double value) const {
  State& s = own<State>(state);
  if (!std::isfinite(value))
    throw InputError(name() + ": command: expected a finite number, got " + formatNumber(value));
  if (!s.held || s.command != value) {
    s.held = true;
    s.command = value;
    s.inputsChanged();
  }
}

void JointRig::releaseCommand(sim::PlantState& state) const {
  State& s = own<State>(state);
  if (s.held) {
    s.held = false;
    s.inputsChanged();
  }
}

std::vector<sim::InputPort> JointRig::inputPorts() const {
  sim::InputPort c;
  c.name = "command";
  switch (s_.input) {
    case RigInput::MotorTorque:
      c.unit = "N·m";
      c.description = "motor torque";
      break;
    case RigInput::Voltage:
      c.unit = "V";
      c.description = "motor voltage";
      break;
    case RigInput::VelocityPI:
      c.unit = "rad/s";
      c.description = "velocity reference of the PI loop";
      break;
  }
  c.description += " (held in place of the input profile)";
  std::vector<sim::InputPort> out{c};
  if (!s_.clamped) {
    sim::InputPort l;
    l.name = "load_torque";
    l.unit = "N·m";
    l.description = "external torque on the output shaft";
    out.push_back(l);
  }
  return out;
}

void JointRig::setInput(sim::PlantState& state, int port, double value) const {
  if (port == 0) return setCommand(state, value);
  if (port == 1 && !s_.clamped) return setLoadTorque(state, value);
  throw InputError(name() + ": input " + std::to_string(port) + " out of range 0.." + (s_.clamped ? "0" : "1"));
}

double JointRig::input(const sim::PlantState& state, int port) const {
  const State& s = own<State>(state);
  if (port == 0) return s.command;
  if (port == 1 && !s_.clamped) return s.load_torque;
  throw InputError(name() + ": input " + std::to_string(port) + " out of range 0.." + (s_.clamped ? "0" : "1"));
}

bool JointRig::inputActive(const sim::PlantState& state, int port) const {
  (void)input(state, port);  // range check
  return port == 1 || own<State>(state).held;
}

void JointRig::releaseInput(sim::PlantState& state, int port) const {
  (void)input(state, port);  // range check
  if (port == 0)
    releaseCommand(state);
  else
    setLoadTorque(state, 0.0);
}

void JointRig::setLoadTorque(sim::PlantState& state, double tau) const {
  State& s = own<State>(state);
  if (!std::isfinite(tau))
    throw InputError(name() + ": load torque: expected a finite number, got " + formatNumber(tau));
  if (s_.clamped && tau != 0.0) throw InputError(name() + ": load torque: the output is clamped");
  if (s.load_torque != tau) {
    s.load_torque = tau;
    s.inputsChanged();
  }
}

std::string JointRig::name() const { return "joint rig '" + s_.name + "'"; }

std::vector<double> JointRig::timeEvents(double t_end) const {
  std::vector<double> events = s_.profile.breakpoints(t_end);
  if (s_.load_torque)
    for (double b : s_.load_torque->breakpoints(t_end)) events.push_back(b);
  return events;
}

sim::SimulateOptions JointRig::simulateOptions() const {
  return sim::SimulateOptions::atRate(s_.duration, s_.log_rate, s_.solver);
}

Eigen::VectorXd JointRig::initialState() const {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(n_);
  y[0] = s_.q_m0;
  y[1] = s_.qd_m0;
  const double q_l0 = s_.transmission->isRigid() ? s_.q_m0 / s_.transmission->ratio() : (s_.clamped ? 0.0 : s_.q_l0);
  if (nx_ > 0) s_.transmission->initialState(s_.q_m0, q_l0, y.data() + x_idx_);
  if (nz_ > 0) s_.friction->initialState(y.data() + z_idx_);
  if (l_idx_ >= 0) {
    y[l_idx_] = s_.q_l0;
    y[l_idx_ + 1] = s_.qd_l0;
  }
  return y;
}

JointRig::Eval JointRig::evaluate(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                                  double* xdot_tr, double* zdot) const {
  Eval e;
  const double q_m = y[0], qd_m = y[1];
  const double N = s_.transmission->ratio();
  const bool rigid = s_.transmission->isRigid();
  if (rigid) {
    e.q_l = q_m / N;
    e.qd_l = qd_m / N;
  } else if (l_idx_ >= 0) {
    e.q_l = y[l_idx_];
    e.qd_l = y[l_idx_ + 1];
  }
  // Input: torque, voltage, or the velocity PI output.
  e.command = st.held ? st.command : s_.profile.value(t);
  double u = e.command;
  if (s_.input == RigInput::VelocityPI) {
    const double err = e.command - (s_.pi.measure == Side::Motor ? qd_m : e.qd_l);
    u = control::velocityPi(s_.pi.kp, s_.pi.ki, s_.pi.limit, err, y[e_idx_], e.de);
  }
  if (i_idx_ >= 0) {
    e.current = y[i_idx_];
    e.voltage = motor_->supplyVoltage(u);
    e.di = motor_->currentDerivative(e.current, u, qd_m);
    e.tau_motor = motor_->torque(e.current);
  } else {
    e.tau_motor = u;
  }
  const double* z = nz_ > 0 ? y.data() + z_idx_ : nullptr;
  const double b_l = s_.clamped ? 0.0 : s_.load_damping;
  // External load on the output shaft: the port's value plus the file's profile [N·m].
  e.tau_load = s_.clamped ? 0.0 : st.load_torque + (s_.load_torque ? s_.load_torque->value(t) : 0.0);

  if (rigid) {
    // One shaft, motor side: (J_m + J_l/N²) q̈_m = τ_M − b_l q̇_l / N − τ_f (reflected when on the output).
    const double J_eff = J_m_ + s_.load_inertia / (N * N);
    double tau_f_motor_side = 0.0;
    if (s_.friction) {
      if (s_.friction_side == Side::Motor) {
        e.tau_f = s_.friction->evaluate({qd_m, e.tau_motor + (e.tau_load - b_l * e.qd_l) / N}, z, zdot);
        tau_f_motor_side = e.tau_f;
      } else {
        e.tau_f = s_.friction->evaluate({e.qd_l, N * e.tau_motor + e.tau_load - b_l * e.qd_l}, z, zdot);
        tau_f_motor_side = e.tau_f / N;
      }
    }
    e.qdd_m = (e.tau_motor + (e.tau_load - b_l * e.qd_l) / N - tau_f_motor_side) / J_eff;
    e.qdd_l = e.qdd_m / N;
    const double tau_f_on_motor = (s_.friction && s_.friction_side == Side::Motor) ? e.tau_f : 0.0;
    e.tau_in = e.tau_motor - tau_f_on_motor - J_m_ * e.qdd_m;
    e.tau_out = N * e.tau_in;
    return e;
  }
  const drive::PortTorques pt =
      s_.transmission->evaluate({q_m, qd_m, e.q_l, e.qd_l}, nx_ > 0 ? y.data() + x_idx_ : nullptr, xdot_tr);
  e.tau_in = pt.tau_in;
  e.tau_out = pt.tau_out;
  const double drive_m = e.tau_motor - e.tau_in;
  double drive_l = e.tau_out - b_l * e.qd_l;
  drive_l += e.tau_load;
  double tau_f_m = 0.0, tau_f_l = 0.0;
  if (s_.friction) {
    if (s_.friction_side == Side::Motor) {
      e.tau_f = tau_f_m = s_.friction->evaluate({qd_m, drive_m}, z, zdot);
    } else {
      e.tau_f = tau_f_l = s_.friction->evaluate({e.qd_l, drive_l}, z, zdot);
    }
  }
  e.qdd_m = (drive_m - tau_f_m) / J_m_;
  e.qdd_l = s_.clamped ? 0.0 : (drive_l - tau_f_l) / s_.load_inertia;
  return e;
}

void JointRig::derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                           Eigen::Ref<Eigen::VectorXd> ydot) const {
  const Eval e = evaluate(own<State>(state), t, y, nx_ > 0 ? ydot.data() + x_idx_ : nullptr,
                          nz_ > 0 ? ydot.data() + z_idx_ : nullptr);
  ydot[0] = y[1];
  ydot[1] = e.qdd_m;
  if (i_idx_ >= 0) ydot[i_idx_] = e.di;
  if (l_idx_ >= 0) {
    ydot[l_idx_] = y[l_idx_ + 1];
    ydot[l_idx_ + 1] = e.qdd_l;
  }
  if (e_idx_ >= 0) ydot[e_idx_] = e.de;
}

void JointRig::signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                       Eigen::Ref<Eigen::VectorXd> row) const {
  // Scratch for derivatives we do not need here (state sizes are small; a fixed buffer avoids allocation).
  double xdot[64], zdot[64];
  const Eval e = evaluate(own<State>(state), t, y, nx_ > 0 ? xdot : nullptr, nz_ > 0 ? zdot : nullptr);
  Eigen::Index k = 0;
  row[k++] = y[0];
  row[k++] = y[1];
  row[k++] = e.tau_motor;
  if (i_idx_ >= 0) {
    row[k++] = e.current;
    row[k++] = e.voltage;
  }
  row[k++] = e.command;
  if (s_.load_torque) row[k++] = e.tau_load;
  row[k++] = e.tau_in;
  row[k++] = e.tau_out;
  row[k++] = e.tau_f;
  row[k++] = e.q_l;
  row[k++] = e.qd_l;
  for (int j = 0; j < nx_; ++j) row[k++] = y[x_idx_ + j];
  for (int j = 0; j < nz_; ++j) row[k++] = y[z_idx_ + j];
  if (e_idx_ >= 0) row[k++] = y[e_idx_];
}

}  // namespace jointsim::systems
