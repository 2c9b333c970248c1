#include "jointsim/experiments/passive_robot.hpp"

#include <chrono>
#include <cmath>

#include "jointsim/common/error.hpp"
#include "jointsim/multibody/algorithms.hpp"

namespace jointsim::experiments {

using multibody::Data;
using multibody::Model;

sim::CvodeOptions PassiveRobotParams::defaultSolver() {
  sim::CvodeOptions o;
  o.method = sim::Method::Adams;
  o.rtol = 1e-8;
  o.atol = 1e-10;
  return o;
}

void PassiveRobotParams::validate(const Model& model) const {
  auto checkSize = [&](const Eigen::VectorXd& v, const char* what) {
    if (v.size() != 0 && v.size() != model.nq)
      throw InputError(std::string(what) + ": expected " + std::to_string(model.nq) + " values (one per joint of '" +
                       model.name + "'), got " + std::to_string(v.size()));
  };
  checkSize(q0, "initial_state.q");
  checkSize(qd0, "initial_state.qd");
  checkSize(damping, "joint_damping");
  if (damping.size() && damping.minCoeff() < 0.0) throw InputError("joint_damping: expected values >= 0 N·m·s/rad");
  if (!(duration > 0.0) || !std::isfinite(duration)) throw InputError("duration: expected a time > 0 s");
  if (!(log_rate > 0.0) || !std::isfinite(log_rate)) throw InputError("log_rate: expected a rate > 0 Hz");
}

std::vector<std::string> passiveRobotColumns(const Model& model) {
  std::vector<std::string> cols{"time[s]"};
  auto unit = [&](size_t i, const char* rev, const char* pri) {
    return model.joint_types[i] == multibody::JointType::Revolute ? rev : pri;
  };
  for (size_t i = 0; i < static_cast<size_t>(model.nq); ++i)
    cols.push_back("q_" + model.joint_names[i] + "[" + unit(i, "rad", "m") + "]");
  for (size_t i = 0; i < static_cast<size_t>(model.nq); ++i)
    cols.push_back("qd_" + model.joint_names[i] + "[" + unit(i, "rad/s", "m/s") + "]");
  for (const char* c : {"kinetic_energy[J]", "potential_energy[J]", "total_energy[J]"}) cols.emplace_back(c);
  for (const char* axis : {"x", "y", "z"}) cols.push_back("tip_" + std::string(axis) + "[m]");
  return cols;
}

PassiveRobotResult simulatePassiveRobot(const Model& model, const PassiveRobotParams& params,
                                        const std::function<void(const Eigen::VectorXd& row)>& sink) {
  params.validate(model);
  const Eigen::Index n = model.nq;
  Data data(model);
  const Eigen::VectorXd damping = params.damping.size() ? params.damping : Eigen::VectorXd::Zero(n);
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(n);

  // ẏ = [q̇; ABA(q, q̇, −b q̇)] with y = [q; q̇].
  auto rhs = [&](double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> ydot) {
    tau.noalias() = -damping.cwiseProduct(y.tail(n));
    ydot.head(n) = y.tail(n);
    ydot.tail(n) = multibody::aba(model, data, y.head(n), y.tail(n), tau);
  };
  sim::CvodeOptions solver = params.solver;
  if (solver.component.empty()) solver.component = "multibody (" + model.name + ")";
  sim::CvodeIntegrator integrator(static_cast<int>(2 * n), rhs, solver);

  Eigen::VectorXd y(2 * n);
  y.head(n) = params.q0.size() ? params.q0 : Eigen::VectorXd::Zero(n);
  y.tail(n) = params.qd0.size() ? params.qd0 : Eigen::VectorXd::Zero(n);

  const int tip = model.frameIndex(model.tip_frame);
  Data log_data(model);
  Eigen::VectorXd row(1 + 2 * n + 6);
  auto emit = [&](double t) {
    const double T = multibody::kineticEnergy(model, log_data, y.head(n), y.tail(n));
    const double V = multibody::potentialEnergy(model, log_data, y.head(n));  // also updates oMf
    row << t, y, T, V, T + V, log_data.oMf[static_cast<size_t>(tip)].p;
    sink(row);
  };

  PassiveRobotResult result;
  const auto start = std::chrono::steady_clock::now();
  integrator.initialize(0.0, y);
  emit(0.0);
  result.samples = 1;
  const auto steps = static_cast<long>(std::ceil(params.duration * params.log_rate - 1e-9));
  for (long k = 1; k <= steps; ++k) {
    const double t_out = std::min(params.duration, static_cast<double>(k) / params.log_rate);
    const double t = integrator.advance(t_out, y);
    emit(t);
    ++result.samples;
    result.sim_time_s = t;
  }
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.stats = integrator.stats();
  return result;
}

}  // namespace jointsim::experiments
