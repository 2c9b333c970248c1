#include "jointsim/systems/passive_robot.hpp"

#include <cmath>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/multibody/algorithms.hpp"

namespace jointsim::systems {

using multibody::Model;

sim::CvodeOptions PassiveRobotParams::defaultSolver() {
  sim::CvodeOptions o;
  o.method = sim::Method::Adams;
  o.rtol = 1e-8;
  o.atol = 1e-10;
  return o;
}

void PassiveRobotParams::validate(const Model& model) const {
  // Keys as in a passive_robot experiment file.
  const char* const c = "passive robot";
  auto checkSize = [&](const Eigen::VectorXd& v, const char* key) {
    check::that(v.size() == 0 || v.size() == model.nq, c, key,
                "expected " + std::to_string(model.nq) + " values (one per joint of '" + model.name + "'), got " +
                    std::to_string(v.size()));
  };
  checkSize(q0, "initial_state.q");
  checkSize(qd0, "initial_state.qd");
  checkSize(damping, "joint_damping");
  for (Eigen::Index i = 0; i < damping.size(); ++i)
    check::nonNegative(c, "joint_damping[" + std::to_string(i) + "]", damping[i], "N·m·s/rad");
  check::positive(c, "duration", duration, "s");
  check::positive(c, "log_rate", log_rate, "Hz");
  joint_limits.validate();
}

PassiveRobot::PassiveRobot(Model model, PassiveRobotParams params) : model_(std::move(model)), p_(std::move(params)) {
  p_.validate(model_);
  const Eigen::Index n = model_.nq;
  damping_ = p_.damping.size() ? p_.damping : Eigen::VectorXd::Zero(n);
  stops_ = EndStops(model_, p_.joint_limits);
  tip_ = model_.frameIndex(model_.tip_frame);
  auto unit = [&](size_t i, const char* rev, const char* pri) {
    return model_.joint_types[i] == multibody::JointType::Revolute ? rev : pri;
  };
  for (size_t i = 0; i < static_cast<size_t>(n); ++i)
    signals_.push_back("q_" + model_.joint_names[i] + "[" + unit(i, "rad", "m") + "]");
  for (size_t i = 0; i < static_cast<size_t>(n); ++i)
    signals_.push_back("qd_" + model_.joint_names[i] + "[" + unit(i, "rad/s", "m/s") + "]");
  for (const char* c : {"kinetic_energy[J]", "potential_energy[J]", "total_energy[J]"}) signals_.emplace_back(c);
  for (size_t i = 0; i < static_cast<size_t>(n); ++i) {
    sim::InputPort p;
    p.name = model_.joint_names[i] + ".torque";
    p.unit = unit(i, "N·m", "N");
    p.description = "torque applied at the joint " + model_.joint_names[i];
    ports_.push_back(p);
  }
  profiles_.resize(ports_.size());
  for (const char* axis : {"x", "y", "z"}) signals_.push_back("tip_" + std::string(axis) + "[m]");
  if (stops_.active()) {
    signals_.emplace_back("end_stop_energy[J]");
    for (int i : stops_.joints())
      signals_.push_back("end_stop_torque_" + model_.joint_names[static_cast<size_t>(i)] + "[" +
                         unit(static_cast<size_t>(i), "N·m", "N") + "]");
  }
}

PassiveRobot::State::State(const PassiveRobot& robot)
    : PlantStateOf(robot), data(robot.model_), log_data(robot.model_) {
  tau.setZero(robot.model_.nq);
  tau_stop.setZero(robot.model_.nq);
  inputs.resize(robot.ports_.size());
}

std::string PassiveRobot::name() const { return "multibody (" + model_.name + ")"; }

sim::SimulateOptions PassiveRobot::simulateOptions() const {
  sim::SimulateOptions o = sim::SimulateOptions::atRate(p_.duration, p_.log_rate, p_.solver);
  o.solver.max_step = p_.solver.max_step;  // smooth dynamics: no step limit unless asked for
  o.stop_at_end = false;
  return o;
}

Eigen::VectorXd PassiveRobot::initialState() const {
  const Eigen::Index n = model_.nq;
  Eigen::VectorXd y(2 * n);
  y.head(n) = p_.q0.size() ? p_.q0 : Eigen::VectorXd::Zero(n);
  y.tail(n) = p_.qd0.size() ? p_.qd0 : Eigen::VectorXd::Zero(n);
  return y;
}

void PassiveRobot::derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                               Eigen::Ref<Eigen::VectorXd> ydot) const {
  const State& st = own<State>(state);
  const Eigen::Index n = model_.nq;
  st.tau.noalias() = -damping_.cwiseProduct(y.tail(n));
  for (Eigen::Index i = 0; i < n; ++i) st.tau[i] += profiles_.value(st.inputs, static_cast<size_t>(i), t);
  if (stops_.active()) {
    stops_.torques(y.head(n), y.tail(n), st.tau_stop);
    st.tau += st.tau_stop;
  }
  ydot.head(n) = y.tail(n);
  ydot.tail(n) = multibody::aba(model_, st.data, y.head(n), y.tail(n), st.tau);
}

void PassiveRobot::signals(const sim::PlantState& state, double, const Eigen::Ref<const Eigen::VectorXd>& y,
                           Eigen::Ref<Eigen::VectorXd> out) const {
  const State& st = own<State>(state);
  const Eigen::Index n = model_.nq;
  const double T = multibody::kineticEnergy(model_, st.log_data, y.head(n), y.tail(n));
  const double V = multibody::potentialEnergy(model_, st.log_data, y.head(n));  // also updates oMf
  const double E_stop = stops_.energy(y.head(n));
  out.head(2 * n) = y;
  out[2 * n] = T;
  out[2 * n + 1] = V;
  out[2 * n + 2] = T + V + E_stop;
  out.segment(2 * n + 3, 3) = st.log_data.oMf[static_cast<size_t>(tip_)].p;
  if (stops_.active()) {
    out[2 * n + 6] = E_stop;
    stops_.torques(y.head(n), y.tail(n), st.tau_stop);
    Eigen::Index c = 2 * n + 7;
    for (int i : stops_.joints()) out[c++] = st.tau_stop[i];
  }
}

void PassiveRobot::roots(const sim::PlantState& /*state*/, double, const Eigen::Ref<const Eigen::VectorXd>& y,
                         Eigen::Ref<Eigen::VectorXd> g) const {
  stops_.roots(y.head(model_.nq), g.data());
}

}  // namespace jointsim::systems
