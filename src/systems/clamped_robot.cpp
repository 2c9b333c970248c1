#include "jointsim/systems/clamped_robot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <utility>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/orthogonal_compliance.hpp"

namespace jointsim::systems {
namespace {

// Rotation vector θ of a rotation matrix R (R = exp([θ]×)), accurate for small angles.
Eigen::Vector3d rotationVector(const Eigen::Matrix3d& R) {
  const Eigen::Vector3d v(0.5 * (R(2, 1) - R(1, 2)), 0.5 * (R(0, 2) - R(2, 0)), 0.5 * (R(1, 0) - R(0, 1)));
  const double s = v.norm(), c = 0.5 * (R.trace() - 1.0);
  return s > 1e-300 ? Eigen::Vector3d(v * (std::atan2(s, c) / s)) : v;
}

}  // namespace

void ClampingAxisParams::validate() const {
  // Key paths as in an experiment file's axis mapping, so that a loader can point at the line.
  const std::string w = "clamping axis '" + joint + "'";
  check::nonZero(w, "ratio", ratio, "(-)");
  check::positive(w, "inertia", inertia, "kg·m²");
  check::positive(w, "c", c, "N·m/rad");
  check::nonNegative(w, "d", d, "N·m·s/rad");
  check::nonNegative(w, "b", b, "rad");
  check::that(!tau_pos.empty(), w, "friction.tau_pos", "needs at least one row [w in rad/s, tau in N·m]");
  for (size_t i = 0; i < tau_pos.size(); ++i) {
    const std::string row = "friction.tau_pos[" + std::to_string(i) + "]";
    check::nonNegative(w, row, tau_pos[i][1], "N·m (friction torque)");
    if (i == 0) check::that(tau_pos[0][0] == 0.0, w, row, "the table must start at w = 0 rad/s");
    if (i > 0) check::that(tau_pos[i][0] > tau_pos[i - 1][0], w, row, "the table speeds must increase");
  }
  check::atLeast(w, "friction.peak", peak, 1.0, "(-)");
  check::nonNegative(w, "orthogonal.c", c_orth, "N·m/rad");
  check::nonNegative(w, "orthogonal.d", d_orth, "N·m·s/rad");
  check::positive(w, "controller.Ts", Ts, "s");
  check::nonNegative(w, "controller.kp", kp, "1/s");
  check::nonNegative(w, "controller.ks", ks, "N·m·s/rad");
  check::finite(w, "controller.ratio", controller_ratio, "(-)");
  try {
    path.validate();
  } catch (const InputError& e) {
    throw InputError::parameter(w, "path." + e.keyPath(), e.message());
  }
}

sim::CvodeOptions ClampingSetup::defaultSolver() { return sim::stiffDriveSolver(1e-6, 1e-9); }

void ClampingSetup::validate() const {
  if (static_cast<int>(axes.size()) != arm.nq)
    throw InputError("clamping: expected one axis per movable joint of '" + arm.name + "' (" + std::to_string(arm.nq) +
                     "), got " + std::to_string(axes.size()));
  std::set<std::string> seen;
  for (const auto& a : axes) {
    a.validate();
    arm.jointIndex(a.joint);
    if (!seen.insert(a.joint).second) throw InputError("clamping: joint '" + a.joint + "' has two axes");
  }
  if (coupling.size() > 0) {
    if (coupling.rows() != coupling.cols() || coupling.rows() != static_cast<Eigen::Index>(coupled_joints.size()))
      throw InputError("clamping: coupling must be square with one row per coupled joint");
    std::set<std::string> coupled;
    for (const auto& j : coupled_joints)
      if (!coupled.insert(j).second) throw InputError("clamping: joint '" + j + "' appears twice in the coupling");
    if (std::abs(coupling.determinant()) < 1e-300) throw InputError("clamping: coupling matrix is singular");
    for (const auto& j : coupled_joints) arm.jointIndex(j);
  }
  if (q0.size() != 0 && q0.size() != arm.nq)
    throw InputError("clamping: q0 needs one angle per joint (" + std::to_string(arm.nq) + ")");
  if (!(duration > 0.0) || !(log_interval > 0.0)) throw InputError("clamping: duration and log interval must be > 0 s");
  for (const Eigen::Matrix3d* m : {&clamp.c_lin, &clamp.d_lin, &clamp.c_rot, &clamp.d_rot})
    if (!m->allFinite()) throw InputError("clamping: clamp matrices must be finite");
}

ClampedRobot::ClampedRobot(ClampingSetup setup) : s_((setup.validate(), std::move(setup))) {
  n_ = s_.arm.nq;
  std::vector<std::string> orth_joints;
  for (const auto& a : s_.axes)
    if (a.c_orth > 0.0) orth_joints.push_back(a.joint);
  model_ = multibody::withOrthogonalCompliance(s_.arm, orth_joints);
  n_states_ = 2 * model_.nq + 3 * n_;
  for (const auto& a : s_.axes) {
    joint_.push_back(model_.jointIndex(a.joint));
    if (a.c_orth > 0.0)
      orth_.push_back({model_.jointIndex(a.joint + "_orth_u"), model_.jointIndex(a.joint + "_orth_v")});
    else
      orth_.push_back({-1, -1});
    drive::ElastoBacklashParams p;
    p.ratio = 1.0;
    p.stiffness = a.c;
    p.damping = a.d;
    p.backlash = a.b;
    eb_.emplace_back(p);
    controllers_.push_back(control::JointController::torqueCascade(a.kp, a.ks, a.Ts));
    paths_.emplace_back(a.path);
  }
  // Coupling over the axes (axis order): q_axis = G φ_out.
  Gfull_ = Eigen::MatrixXd::Identity(n_, n_);
  if (s_.coupling.size() > 0) {
    std::vector<int> idx;
    for (const auto& j : s_.coupled_joints) {
      int k = -1;
      for (int a = 0; a < n_; ++a)
        if (s_.axes[static_cast<size_t>(a)].joint == j) k = a;
      idx.push_back(k);
    }
    for (size_t r = 0; r < idx.size(); ++r)
      for (size_t c = 0; c < idx.size(); ++c)
        Gfull_(idx[r], idx[c]) = s_.coupling(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c));
    coupled_ = true;
  }
  GfullInv_ = Gfull_.inverse();
  clamp_frame_ = model_.frameIndex(s_.clamp.frame.empty() ? model_.tip_frame : s_.clamp.frame);
  if (model_.frames[static_cast<size_t>(clamp_frame_)].joint < 0)
    throw InputError("clamping: clamp frame '" + model_.frames[static_cast<size_t>(clamp_frame_)].name +
                     "' is on the fixed base; clamp a frame of a moving link (e.g. the tool flange)");
  // Start posture and the clamp's anchor pose.
  Eigen::VectorXd q = Eigen::VectorXd::Zero(model_.nq);
  if (s_.q0.size())
    for (int i = 0; i < n_; ++i) q[model_.jointIndex(s_.arm.joint_names[static_cast<size_t>(i)])] = s_.q0[i];
  multibody::Data data(model_);
  multibody::forwardKinematics(model_, data, q);
  p0_ = data.oMf[static_cast<size_t>(clamp_frame_)].p;
  R0_ = data.oMf[static_cast<size_t>(clamp_frame_)].R;
  Eigen::VectorXd qa(n_);
  for (int k = 0; k < n_; ++k) qa[k] = q[joint_[static_cast<size_t>(k)]];
  const Eigen::VectorXd phi_out = GfullInv_ * qa;
  phi_m0_.resize(n_);
  for (int k = 0; k < n_; ++k) phi_m0_[k] = s_.axes[static_cast<size_t>(k)].ratio * phi_out[k];
  for (const auto& a : s_.axes)
    for (const char* c :
         {".motor_angle[rad]", ".motor_speed[rad/s]", ".motor_torque[N·m]", ".spring_torque[N·m]", ".deflection[rad]",
          ".joint_angle[rad]", ".reference[rad]", ".friction_torque[N·m]", ".friction_mode[-]", ".orth_angle[rad]"})
      signals_.push_back(a.joint + c);
  for (const char* c : {"clamp.dx[m]", "clamp.dy[m]", "clamp.dz[m]", "clamp.rx[rad]", "clamp.ry[rad]", "clamp.rz[rad]",
                        "clamp.displacement[m]", "clamp.rotation[rad]", "clamp.force[N]", "clamp.moment[N·m]"})
    signals_.emplace_back(c);
  for (const auto& a : s_.axes) {
    sim::InputPort m;
    m.name = a.joint + ".motor_torque";
    m.unit = "N·m";
    m.description = "motor torque of the axis of " + a.joint + " (held in place of its controller, which freezes)";
    ports_.push_back(m);
    sim::InputPort l;
    l.name = a.joint + ".load_torque";
    l.unit = "N·m";
    l.description = "external torque at the joint " + a.joint;
    ports_.push_back(l);
  }
  profiles_.resize(ports_.size());
}

ClampedRobot::State::State(const ClampedRobot& robot) : PlantStateOf(robot), data(robot.model_) {
  modes.assign(static_cast<size_t>(robot.n_), FrictionMode::Stuck);
  inputs.resize(robot.ports_.size());
  fext = multibody::Matrix6Xd::Zero(6, robot.model_.nq);
  for (Eigen::VectorXd* v :
       {&tau_out, &qa, &qda, &phi_out, &phid_out, &tau_s, &tau_m, &tau_f, &stuck, &wdot, &xdot, &ref})
    v->setZero(robot.n_);
  tau.setZero(robot.model_.nq);
  dp.setZero();
  theta.setZero();
  f_w.setZero();
  m_w.setZero();
}

void ClampedRobot::State::save(ByteWriter& out) const {
  drive::saveModes(out, modes);
  inputs.save(out);
}

void ClampedRobot::State::load(ByteReader& in) {
  drive::loadModes(in, modes);
  inputs.load(in);
}

const std::vector<FrictionMode>& ClampedRobot::modes(const sim::PlantState& state) const {
  return own<State>(state).modes;
}

Eigen::VectorXd ClampedRobot::initialState() const {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(n_states_);
  if (s_.q0.size())
    for (int i = 0; i < n_; ++i) y[model_.jointIndex(s_.arm.joint_names[static_cast<size_t>(i)])] = s_.q0[i];
  for (int k = 0; k < n_; ++k) {
    const int m = motorState(k);
    y[m] = phi_m0_[k];
    // PI initial output 0 ([Olsson2017, A.12] InitialOutput): x(0) = −u(0), u(0) = r_c q̇_ref(0) (motor at rest,
    // on its reference).
    double q, qd, qdd;
    paths_[static_cast<size_t>(k)].evaluate(0.0, q, qd, qdd);
    const auto& a = s_.axes[static_cast<size_t>(k)];
    y[m + 2] = -(a.controller_ratio * qd + a.kp * a.controller_ratio * q);
  }
  return y;
}

void ClampedRobot::clampDeflection(const sim::PlantState& state, const Eigen::Ref<const Eigen::VectorXd>& q,
                                   Eigen::Vector3d& dp, Eigen::Vector3d& theta) const {
  multibody::Data& data = own<State>(state).data;
  multibody::forwardKinematics(model_, data, q);
  const auto& X = data.oMf[static_cast<size_t>(clamp_frame_)];
  dp = X.p - p0_;
  theta = rotationVector(R0_.transpose() * X.R);
}

void ClampedRobot::solve(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const int nq = model_.nq;
  const auto q = y.head(nq);
  const auto qd = y.segment(nq, nq);
  // Clamp wrench on the clamp frame, applied to the body carrying it.
  multibody::frameJacobian(model_, st.data, q, clamp_frame_);
  const auto& X = st.data.oMf[static_cast<size_t>(clamp_frame_)];
  const Eigen::Matrix<double, 6, 1> vel = st.data.J * qd;  // [v; ω] world
  st.dp = X.p - p0_;
  st.theta = rotationVector(R0_.transpose() * X.R);
  const Eigen::Vector3d w_frame = X.R.transpose() * vel.tail<3>();
  st.f_w = -(s_.clamp.c_lin * st.dp + s_.clamp.d_lin * vel.head<3>());
  st.m_w = X.R * (-(s_.clamp.c_rot * st.theta + s_.clamp.d_rot * w_frame));
  st.fext.setZero();
  {
    const auto& fr = model_.frames[static_cast<size_t>(clamp_frame_)];
    const auto& B = st.data.oMi[static_cast<size_t>(fr.joint)];
    const Eigen::Vector3d f_b = B.R.transpose() * st.f_w;
    const Eigen::Vector3d m_b = B.R.transpose() * st.m_w + fr.placement.p.cross(f_b);
    st.fext.col(fr.joint).head<3>() = m_b;
    st.fext.col(fr.joint).tail<3>() = f_b;
  }
  // Axes: gear output angles, transmission torques, controller, friction.
  for (int k = 0; k < n_; ++k) {
    st.qa[k] = q[joint_[static_cast<size_t>(k)]];
    st.qda[k] = qd[joint_[static_cast<size_t>(k)]];
  }
  if (coupled_) {
    st.phi_out.noalias() = GfullInv_ * st.qa;
    st.phid_out.noalias() = GfullInv_ * st.qda;
  } else {
    st.phi_out = st.qa;
    st.phid_out = st.qda;
  }
  st.tau.setZero();
  for (int k = 0; k < n_; ++k) {
    const auto& a = s_.axes[static_cast<size_t>(k)];
    const int m = motorState(k);
    const double phi_m = y[m], w_m = y[m + 1], x = y[m + 2];
    const double delta = phi_m - a.ratio * st.phi_out[k], delta_d = w_m - a.ratio * st.phid_out[k];
    st.tau_s[k] = eb_[static_cast<size_t>(k)].contactTorque(delta, delta_d);
    double qr, qdr, qddr;
    paths_[static_cast<size_t>(k)].evaluate(t, qr, qdr, qddr);
    st.ref[k] = qr;
    control::ControllerInputs in;  // the axis controller: reference φ_m(0) + r_c q_ref
    in.ratio = a.controller_ratio;
    in.qm_offset = phi_m0_[k];
    in.q_set = qr;
    in.qd_set = qdr;
    in.qm_fb = phi_m;
    in.qdm_fb = w_m;
    st.tau_m[k] = controllers_[static_cast<size_t>(k)].evaluate(in, &x, &st.xdot[k]).u;
    const auto port = static_cast<size_t>(2 * k);  // a held motor torque replaces the controller, frozen
    if (profiles_.active(st.inputs, port)) {
      st.tau_m[k] = profiles_.value(st.inputs, port, t);
      st.xdot[k] = 0.0;
    }
    st.stuck[k] = st.tau_m[k] - st.tau_s[k];
    st.tau_f[k] = drive::frictionTorque(st.modes[static_cast<size_t>(k)],
                                        drive::frictionTableValue(a.tau_pos, std::abs(w_m)), st.stuck[k]);
    st.wdot[k] = st.modes[static_cast<size_t>(k)] == FrictionMode::Stuck
                     ? 0.0
                     : (st.tau_m[k] - st.tau_f[k] - st.tau_s[k]) / a.inertia;
  }
  // Joint torques: τ_out = r τ_s on the gear outputs, τ_joint = G⁻ᵀ τ_out.
  auto& tau_out = st.tau_out;
  for (int k = 0; k < n_; ++k) tau_out[k] = s_.axes[static_cast<size_t>(k)].ratio * st.tau_s[k];
  for (int k = 0; k < n_; ++k) {
    double tj = tau_out[k];
    if (coupled_) tj = GfullInv_.col(k).dot(tau_out);
    st.tau[joint_[static_cast<size_t>(k)]] += tj + profiles_.value(st.inputs, static_cast<size_t>(2 * k + 1), t);
    const auto& o = orth_[static_cast<size_t>(k)];
    if (o[0] >= 0) {
      const auto& a = s_.axes[static_cast<size_t>(k)];
      for (int j : o) st.tau[j] = -a.c_orth * q[j] - a.d_orth * qd[j];
    }
  }
  multibody::aba(model_, st.data, q, qd, st.tau, &st.fext);
}

void ClampedRobot::derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                               Eigen::Ref<Eigen::VectorXd> ydot) const {
  const State& st = own<State>(state);
  solve(st, t, y);
  const int nq = model_.nq;
  ydot.head(nq) = y.segment(nq, nq);
  ydot.segment(nq, nq) = st.data.ddq;
  for (int k = 0; k < n_; ++k) {
    const int m = motorState(k);
    ydot[m] = y[m + 1];
    ydot[m + 1] = st.wdot[k];
    ydot[m + 2] = st.xdot[k];
  }
}

void ClampedRobot::roots(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                         Eigen::Ref<Eigen::VectorXd> g) const {
  const State& st = own<State>(state);
  solve(st, t, y);
  for (int k = 0; k < n_; ++k) {
    const auto& a = s_.axes[static_cast<size_t>(k)];
    const double t0 = drive::frictionTableValue(a.tau_pos, 0.0);
    double g0 = 1, g1 = 1;
    drive::frictionRoots(st.modes[static_cast<size_t>(k)], st.stuck[k], y[motorState(k) + 1], st.wdot[k], t0,
                         a.peak * t0, g0, g1);
    g[2 * k] = g0;
    g[2 * k + 1] = g1;
  }
}

void ClampedRobot::start(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  State& st = own<State>(state);
  std::fill(st.modes.begin(), st.modes.end(), FrictionMode::Stuck);
  updateModes(st, t, y, {});
}

void ClampedRobot::updateModes(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                               const std::vector<int>& fired) const {
  State& st = own<State>(state);
  drive::iterateFrictionModes(
      st.modes.data(), st.modes.size(), fired, [&] { solve(st, t, y); },
      [&](size_t i) {
        const auto k = static_cast<int>(i);
        const auto& a = s_.axes[i];
        drive::FrictionElementView v;
        v.S = st.stuck[k];
        v.w = y[motorState(k) + 1];
        v.a = st.wdot[k];
        v.tau0 = drive::frictionTableValue(a.tau_pos, 0.0);
        v.tau0max = a.peak * v.tau0;
        return v;
      });
}

std::string ClampedRobot::name() const { return "clamping '" + s_.name + "'"; }

sim::SimulateOptions ClampedRobot::simulateOptions() const {
  return sim::SimulateOptions::everyInterval(s_.duration, s_.log_interval, s_.solver);
}

std::vector<double> ClampedRobot::modelTimeEvents(double /*t_end*/) const {
  std::vector<double> t;
  for (const auto& p : paths_)
    for (double b : p.breakpoints()) t.push_back(b);
  std::sort(t.begin(), t.end());
  t.erase(std::unique(t.begin(), t.end()), t.end());
  return t;
}

void ClampedRobot::signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                           Eigen::Ref<Eigen::VectorXd> out) const {
  const State& st = own<State>(state);
  solve(st, t, y);
  Eigen::Index c = 0;
  for (int k = 0; k < n_; ++k) {
    const auto& a = s_.axes[static_cast<size_t>(k)];
    const int m = motorState(k);
    const auto& o = orth_[static_cast<size_t>(k)];
    out[c++] = y[m];
    out[c++] = y[m + 1];
    out[c++] = st.tau_m[k];
    out[c++] = st.tau_s[k];
    out[c++] = y[m] - a.ratio * st.phi_out[k];
    out[c++] = st.qa[k];
    out[c++] = st.ref[k];
    out[c++] = st.tau_f[k];
    out[c++] = drive::frictionModeNumber(st.modes[static_cast<size_t>(k)]);
    out[c++] = o[0] >= 0 ? std::hypot(y[o[0]], y[o[1]]) : 0.0;
  }
  for (int i = 0; i < 3; ++i) out[c++] = st.dp[i];
  for (int i = 0; i < 3; ++i) out[c++] = st.theta[i];
  out[c++] = st.dp.norm();
  out[c++] = st.theta.norm();
  out[c++] = st.f_w.norm();
  out[c++] = st.m_w.norm();
}

bool ClampedRobot::alwaysActive(int port) const { return port % 2 == 1; }

}  // namespace jointsim::systems
