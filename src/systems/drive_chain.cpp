#include "jointsim/systems/drive_chain.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/drive/transmissions.hpp"

namespace jointsim::systems {

using drive::frictionModeNumber;

namespace {
constexpr double kEngageForce = 1e-12;  // [-], relative to fn_max: see DriveChain::roots
}  // namespace

using drive::frictionTableValue;

bool ChainElement::isFriction() const {
  return type == ChainElementType::Clutch || type == ChainElementType::Brake ||
         type == ChainElementType::BearingFriction;
}

sim::CvodeOptions DriveChainSetup::defaultSolver() { return sim::stiffDriveSolver(1e-6, 1e-8); }

void DriveChainSetup::validate() const {
  // Keys as in a drive_chain experiment file (inertias[i], elements[k]).
  const char* const c = "drive chain";
  check::that(!inertias.empty(), c, "inertias", "expected at least one inertia");
  const int n = static_cast<int>(inertias.size());
  for (size_t i = 0; i < inertias.size(); ++i)
    check::positive(c, "inertias[" + std::to_string(i) + "].J", inertias[i].J, "kg·m²");
  for (size_t k = 0; k < elements.size(); ++k) {
    const ChainElement& e = elements[k];
    const std::string key = "elements[" + std::to_string(k) + "]";
    check::that(e.a >= -1 && e.a < n && e.b >= -1 && e.b < n, c, key, "node out of range");
    if (e.type == ChainElementType::TorqueSource) {
      check::that(e.b >= 0, c, key + ".on", "a torque source needs an inertia");
      continue;
    }
    check::that(e.a != e.b, c, key, "both flanges on the same node");
    if (e.type == ChainElementType::Gear) {
      check::that(e.a >= 0 && e.b >= 0, c, key, "a gear joins two inertias");
      check::nonZero(c, key + ".ratio", e.ratio, "(-)");
      const auto& ia = inertias[static_cast<size_t>(e.a)];
      const auto& ib = inertias[static_cast<size_t>(e.b)];
      check::that(std::abs(ia.phi0 - e.ratio * ib.phi0) <= 1e-12 * (1 + std::abs(ia.phi0)) &&
                      std::abs(ia.w0 - e.ratio * ib.w0) <= 1e-12 * (1 + std::abs(ia.w0)),
                  c, key, "initial angles/speeds violate φ_in = ratio·φ_out");
      continue;
    }
    if (e.type == ChainElementType::SpringDamper || e.type == ChainElementType::ElastoBacklash) {
      check::nonNegative(c, key + ".c", e.c, "N·m/rad");
      check::nonNegative(c, key + ".d", e.d, "N·m·s/rad");
    }
    if (e.type == ChainElementType::ElastoBacklash) check::nonNegative(c, key + ".backlash", e.backlash, "rad");
    if (e.isFriction()) {
      check::that(!e.table.empty(), c, key, "empty friction table");
      check::atLeast(c, key + ".peak", e.peak, 1.0, "(-)");
      if (e.type != ChainElementType::BearingFriction) check::nonNegative(c, key + ".fn_max", e.fn_max, "N");
    }
  }
  // Names name the log columns and the input ports (<source>, <inertia>.load_torque): each once.
  std::vector<std::string> names;
  for (const auto& in : inertias) names.push_back(in.name + ".load_torque");
  for (size_t k = 0; k < elements.size(); ++k) {
    const std::string& n = elements[k].name;
    check::that(std::find(names.begin(), names.end(), n) == names.end(), c, "elements[" + std::to_string(k) + "].name",
                "'" + n + "' is the name of another element or input");
    names.push_back(n);
  }
  for (size_t i = 0; i < inertias.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      check::that(inertias[i].name != inertias[j].name, c, "inertias[" + std::to_string(i) + "].name",
                  "'" + inertias[i].name + "' names another inertia");
  check::positive(c, "duration", duration, "s");
  check::positive(c, "log_rate", log_rate, "Hz");
}

DriveChain::State::State(const DriveChain& chain) : PlantStateOf(chain) {
  const auto n = static_cast<Eigen::Index>(chain.s_.inertias.size());
  const auto ne = static_cast<Eigen::Index>(chain.s_.elements.size());
  modes.assign(chain.s_.elements.size(), FrictionMode::Stuck);
  acc.setZero(n);
  known.setZero(n);
  tau_el.setZero(ne);
  A.setZero(ne, ne);
  rhs.setZero(ne);
  stuck.assign(chain.s_.elements.size(), -1);  // sized once: a copy keeps the size (not a reserved capacity)
  inputs.resize(chain.ports_.size());
}

void DriveChain::State::save(ByteWriter& out) const {
  drive::saveModes(out, modes);
  inputs.save(out);
}

void DriveChain::State::load(ByteReader& in) {
  drive::loadModes(in, modes);
  inputs.load(in);
}

const std::vector<FrictionMode>& DriveChain::modes(const sim::PlantState& state) const {
  return own<State>(state).modes;
}

DriveChain::DriveChain(DriveChainSetup setup) : s_(std::move(setup)) {
  s_.validate();
  for (const auto& e : s_.elements)
    backlash_.push_back(e.type == ChainElementType::ElastoBacklash
                            ? std::make_shared<const drive::ElastoBacklash>(drive::ElastoBacklashParams{
                                  1.0, std::max(e.c, 1e-300), e.d, e.backlash, drive::ComplianceSide::Motor})
                            : nullptr);
  int slot = 2 * static_cast<int>(s_.elements.size());
  for (const auto& e : s_.elements)
    normal_slot_.push_back(e.type == ChainElementType::Clutch || e.type == ChainElementType::Brake ? slot++ : -1);
  root_count_ = slot;
  for (const auto& e : s_.elements) {
    source_port_.push_back(-1);
    if (e.type != ChainElementType::TorqueSource) continue;
    source_port_.back() = static_cast<int>(ports_.size());
    sim::InputPort p;
    p.name = e.name;
    p.unit = "N·m";
    p.description = "torque of the source '" + e.name + "' on '" + s_.inertias[static_cast<size_t>(e.b)].name +
                    "' (held in place of its profile)";
    ports_.push_back(p);
  }
  for (const auto& in : s_.inertias) {  // after the sources: inputActive counts on it
    load_port_.push_back(static_cast<int>(ports_.size()));
    sim::InputPort p;
    p.name = in.name + ".load_torque";
    p.unit = "N·m";
    p.description = "external torque on the inertia '" + in.name + "'";
    ports_.push_back(p);
  }
  profiles_.resize(ports_.size());
  for (const auto& in : s_.inertias) {
    signals_.push_back(in.name + ".phi[rad]");
    signals_.push_back(in.name + ".w[rad/s]");
  }
  for (const auto& e : s_.elements) {
    if (e.type == ChainElementType::TorqueSource) {
      signals_.push_back(e.name + ".tau[N·m]");
      continue;
    }
    signals_.push_back(e.name + ".phi_rel[rad]");
    signals_.push_back(e.name + ".w_rel[rad/s]");
    signals_.push_back(e.name + ".tau[N·m]");
    if (e.isFriction()) {
      signals_.push_back(e.name + ".mode[-]");
      signals_.push_back(e.name + ".startForward[-]");
      signals_.push_back(e.name + ".startBackward[-]");
    }
  }
}

Eigen::VectorXd DriveChain::initialState() const {
  Eigen::VectorXd y(stateSize());
  for (size_t i = 0; i < s_.inertias.size(); ++i) {
    y[static_cast<Eigen::Index>(2 * i)] = s_.inertias[i].phi0;
    y[static_cast<Eigen::Index>(2 * i + 1)] = s_.inertias[i].w0;
  }
  return y;
}

double DriveChain::relSpeed(int e, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const auto& el = s_.elements[static_cast<size_t>(e)];
  const double wa = el.a >= 0 ? y[2 * el.a + 1] : 0.0, wb = el.b >= 0 ? y[2 * el.b + 1] : 0.0;
  return wb - wa;
}

double DriveChain::relAccel(const State& st, int e) const {
  const auto& el = s_.elements[static_cast<size_t>(e)];
  return (el.b >= 0 ? st.acc[el.b] : 0.0) - (el.a >= 0 ? st.acc[el.a] : 0.0);
}

double DriveChain::normalForce(int e, double t) const {
  const auto& el = s_.elements[static_cast<size_t>(e)];
  if (el.type == ChainElementType::BearingFriction) return 1.0;  // no normal force: never free
  return el.fn_max * el.normalized.value(t);
}

double DriveChain::tau0(int e, double t) const {
  const auto& el = s_.elements[static_cast<size_t>(e)];
  if (el.type == ChainElementType::BearingFriction) return frictionTableValue(el.table, 0.0);
  return el.cgeo * el.fn_max * el.normalized.value(t) * frictionTableValue(el.table, 0.0);
}

double DriveChain::slidingTorque(int e, double t, double w) const {
  const auto& el = s_.elements[static_cast<size_t>(e)];
  const double mag = el.type == ChainElementType::BearingFriction
                         ? frictionTableValue(el.table, std::abs(w))
                         : el.cgeo * el.fn_max * el.normalized.value(t) * frictionTableValue(el.table, std::abs(w));
  return mag;
}

void DriveChain::solve(const State& st, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  Eigen::VectorXd &known = st.known, &tau_el = st.tau_el, &acc = st.acc, &rhs = st.rhs;
  Eigen::MatrixXd& A = st.A;
  std::vector<int>& stuck = st.stuck;
  int& n_stuck = st.n_stuck;
  known.setZero();
  n_stuck = 0;
  for (size_t k = 0; k < s_.elements.size(); ++k) {
    const auto& el = s_.elements[k];
    const int e = static_cast<int>(k);
    double tau = 0.0;
    if (el.type == ChainElementType::TorqueSource) {
      const int port = source_port_[k];
      tau_el[e] = profiles_.active(st.inputs, static_cast<size_t>(port))
                      ? profiles_.value(st.inputs, static_cast<size_t>(port), t)
                      : el.torque.value(t);
      known[el.b] += tau_el[e];
      continue;
    }
    if (el.type == ChainElementType::Gear) {
      stuck[static_cast<size_t>(n_stuck++)] = e;  // always-active constraint
      continue;
    }
    const double phi_rel = (el.b >= 0 ? y[2 * el.b] : 0.0) - (el.a >= 0 ? y[2 * el.a] : 0.0);
    const double w_rel = relSpeed(e, y);
    switch (el.type) {
      case ChainElementType::SpringDamper: tau = el.c * phi_rel + el.d * w_rel; break;
      case ChainElementType::ElastoBacklash:
        tau = el.c > 0.0 ? backlash_[static_cast<size_t>(e)]->contactTorque(phi_rel, w_rel) : 0.0;
        break;
      default: {  // friction
        switch (st.modes[k]) {
          case FrictionMode::Free: tau = 0.0; break;
          case FrictionMode::Forward:
          case FrictionMode::StartForward: tau = slidingTorque(e, t, w_rel); break;
          case FrictionMode::Backward:
          case FrictionMode::StartBackward: tau = -slidingTorque(e, t, w_rel); break;
          case FrictionMode::Stuck: stuck[static_cast<size_t>(n_stuck++)] = e; continue;
        }
      }
    }
    tau_el[e] = tau;
    if (el.a >= 0) known[el.a] += tau;
    if (el.b >= 0) known[el.b] -= tau;
  }
  for (size_t i = 0; i < s_.inertias.size(); ++i)  // external torques at the load ports (0 until set)
    known[static_cast<Eigen::Index>(i)] += profiles_.value(st.inputs, static_cast<size_t>(load_port_[i]), t);
  // Stuck elements: find their torques S with B^T J⁻¹ (known + B S) = 0 (zero relative acceleration).
  const auto m = static_cast<Eigen::Index>(n_stuck);
  auto Jinv = [&](int i) { return 1.0 / s_.inertias[static_cast<size_t>(i)].J; };
  // Constraint row of element e: +1 at its input, −1 (friction) or −ratio (gear) at its output; the
  // constraint torque acts along the same row (+τ on the input, −1 or −ratio × τ on the output).
  auto bcol = [&](int e, int i) {
    const auto& el = s_.elements[static_cast<size_t>(e)];
    const double out = el.type == ChainElementType::Gear ? el.ratio : 1.0;
    return (el.a == i ? 1.0 : 0.0) - (el.b == i ? out : 0.0);
  };
  const int n = static_cast<int>(s_.inertias.size());
  for (Eigen::Index r = 0; r < m; ++r) {
    const int er = stuck[static_cast<size_t>(r)];
    double sum = 0.0;
    for (int i = 0; i < n; ++i) sum -= bcol(er, i) * Jinv(i) * known[i];
    rhs[r] = sum;
    for (Eigen::Index c = 0; c < m; ++c) {
      const int ec = stuck[static_cast<size_t>(c)];
      double a = 0.0;
      for (int i = 0; i < n; ++i) a += bcol(er, i) * Jinv(i) * bcol(ec, i);
      A(r, c) = a;
    }
  }
  // Gaussian elimination with partial pivoting on the m×m block (allocation-free).
  for (Eigen::Index c = 0; c < m; ++c) {
    Eigen::Index piv = c;
    for (Eigen::Index r = c + 1; r < m; ++r)
      if (std::abs(A(r, c)) > std::abs(A(piv, c))) piv = r;
    if (piv != c) {
      A.row(c).head(m).swap(A.row(piv).head(m));
      std::swap(rhs[c], rhs[piv]);
    }
    if (A(c, c) == 0.0) continue;  // redundant constraint (e.g. a loop of stuck elements)
    for (Eigen::Index r = c + 1; r < m; ++r) {
      const double f = A(r, c) / A(c, c);
      A.row(r).head(m) -= f * A.row(c).head(m);
      rhs[r] -= f * rhs[c];
    }
  }
  for (Eigen::Index c = m; c-- > 0;) {
    double v = rhs[c];
    for (Eigen::Index k = c + 1; k < m; ++k) v -= A(c, k) * rhs[k];
    rhs[c] = A(c, c) != 0.0 ? v / A(c, c) : 0.0;
  }
  for (Eigen::Index r = 0; r < m; ++r) {
    const int e = stuck[static_cast<size_t>(r)];
    const auto& el = s_.elements[static_cast<size_t>(e)];
    tau_el[e] = rhs[r];
    if (el.a >= 0) known[el.a] += rhs[r];
    if (el.b >= 0) known[el.b] -= (el.type == ChainElementType::Gear ? el.ratio : 1.0) * rhs[r];
  }
  for (int i = 0; i < n; ++i) acc[i] = known[i] * Jinv(i);
}

void DriveChain::derivatives(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                             Eigen::Ref<Eigen::VectorXd> ydot) const {
  const State& st = own<State>(state);
  solve(st, t, y);
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(s_.inertias.size()); ++i) {
    ydot[2 * i] = y[2 * i + 1];
    ydot[2 * i + 1] = st.acc[i];
  }
}

void DriveChain::roots(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                       Eigen::Ref<Eigen::VectorXd> g) const {
  const State& st = own<State>(state);
  solve(st, t, y);
  for (size_t k = 0; k < s_.elements.size(); ++k) {
    const auto& el = s_.elements[k];
    const int e = static_cast<int>(k);
    double g0 = 1.0, g1 = 1.0;
    if (el.type == ChainElementType::ElastoBacklash && el.backlash > 1e-10) {
      const double phi_rel = (el.b >= 0 ? y[2 * el.b] : 0.0) - (el.a >= 0 ? y[2 * el.a] : 0.0);
      g0 = phi_rel - 0.5 * el.backlash;  // contact edges: restart the integrator at the kink
      g1 = phi_rel + 0.5 * el.backlash;
    } else if (el.isFriction()) {
      const double t0 = tau0(e, t), t0max = el.peak * t0, w = relSpeed(e, y), a = relAccel(st, e);
      drive::frictionRoots(st.modes[k], st.tau_el[e], w, a, t0, t0max, g0, g1);
    }
    g[2 * e] = g0;
    g[2 * e + 1] = g1;
    // MSL: free = fn <= 0, a state event. A free element engages where fn exceeds kEngageForce·fn_max: a normal force
    // that starts at zero (a sine from t = 0) leaves zero at a restart, which CVODE does not report as a root.
    if (normal_slot_[k] >= 0)
      g[normal_slot_[k]] = normalForce(e, t) - (st.modes[k] == FrictionMode::Free ? kEngageForce * el.fn_max : 0.0);
  }
}

std::string DriveChain::name() const { return "drive chain '" + s_.name + "'"; }

sim::SimulateOptions DriveChain::simulateOptions() const {
  return sim::SimulateOptions::atRate(s_.duration, s_.log_rate, s_.solver);
}

std::vector<double> DriveChain::modelTimeEvents(double t_end) const {
  // Discontinuities of the torque sources and normal forces.
  std::vector<double> events;
  for (const auto& el : s_.elements) {
    for (double b : el.torque.breakpoints(t_end)) events.push_back(b);
    for (double b : el.normalized.breakpoints(t_end)) events.push_back(b);
  }
  return events;
}

void DriveChain::start(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  State& st = own<State>(state);
  for (size_t k = 0; k < s_.elements.size(); ++k) {
    if (!s_.elements[k].isFriction()) continue;
    const double w = relSpeed(static_cast<int>(k), y);
    st.modes[k] = normalForce(static_cast<int>(k), t) <= 0.0
                      ? FrictionMode::Free
                      : (w > 0 ? FrictionMode::Forward : (w < 0 ? FrictionMode::Backward : FrictionMode::Stuck));
  }
  updateModes(st, t, y, {});
}

void DriveChain::updateModes(sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                             const std::vector<int>& fired) const {
  State& st = own<State>(state);
  drive::iterateFrictionModes(
      st.modes.data(), st.modes.size(), fired, [&] { solve(st, t, y); },
      [&](size_t k) {
        drive::FrictionElementView v;
        const auto& el = s_.elements[k];
        v.friction = el.isFriction();
        if (!v.friction) return v;
        const int e = static_cast<int>(k);
        v.S = st.tau_el[e];
        v.w = relSpeed(e, y);
        v.a = relAccel(st, e);
        v.tau0 = tau0(e, t);
        v.tau0max = el.peak * v.tau0;
        v.fn = normalForce(e, t);
        v.normal_slot = normal_slot_[k];
        return v;
      });
}

double DriveChain::elementTorque(const sim::PlantState& state, int e, double t,
                                 const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const State& st = own<State>(state);
  solve(st, t, y);
  return st.tau_el[e];
}

void DriveChain::signals(const sim::PlantState& state, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                         Eigen::Ref<Eigen::VectorXd> row) const {
  const State& st = own<State>(state);
  solve(st, t, y);
  Eigen::Index c = 0;
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(s_.inertias.size()); ++i) {
    row[c++] = y[2 * i];
    row[c++] = y[2 * i + 1];
  }
  for (size_t k = 0; k < s_.elements.size(); ++k) {
    const auto& el = s_.elements[k];
    const int e = static_cast<int>(k);
    if (el.type == ChainElementType::TorqueSource) {
      row[c++] = st.tau_el[e];
      continue;
    }
    row[c++] = (el.b >= 0 ? y[2 * el.b] : 0.0) - (el.a >= 0 ? y[2 * el.a] : 0.0);
    row[c++] = relSpeed(e, y);
    row[c++] = st.tau_el[e];
    if (el.isFriction()) {
      row[c++] = frictionModeNumber(st.modes[k]);
      row[c++] = st.modes[k] == FrictionMode::StartForward ? 1.0 : 0.0;
      row[c++] = st.modes[k] == FrictionMode::StartBackward ? 1.0 : 0.0;
    }
  }
}

bool DriveChain::alwaysActive(int port) const {
  return port >= static_cast<int>(ports_.size()) - static_cast<int>(s_.inertias.size());
}

}  // namespace jointsim::systems
