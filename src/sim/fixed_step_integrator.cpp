// The fixed-step Rosenbrock-W integrator ROS2 [Verwer1999] (fixed_step_integrator.hpp).
#include "jointsim/sim/fixed_step_integrator.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <string>
#include <utility>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "sim/block_linear_solver.hpp"
#include "sim/callback_exception.hpp"

namespace jointsim::sim {

namespace {
/// ROS2's γ = 1 + 1/√2 [Verwer1999, eq. 2.3]: L-stable, and the error constant of the second-order pair smallest.
const double kGamma = 1.0 + 1.0 / std::sqrt(2.0);
/// The other root of γ² − 2γ + 1/2 = 0 (R(∞) = 0: also L-stable), 1 − 1/√2, as a factor on W's rows: the method's
/// coefficients do not depend on γ, so γ only multiplies W (and fₜ), and rows scaled by this ratio are taken with it
/// (exactly so for a right-hand side free of t; with fₜ ≠ 0 those rows keep γ = 1 + 1/√2's γh·fₜ: still a W-method
/// of order 2).
const double kOscillatoryRowScale = (1.0 - 1.0 / std::sqrt(2.0)) / kGamma;
constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kNoTime = std::numeric_limits<double>::quiet_NaN();  // unset time [s]
/// A step shorter than this fraction of the fixed step is not taken: the grid point or stop time this close is
/// merged with the one after it (rounding of k·h against a stop time computed another way).
constexpr double kMergeFraction = 1e-6;
/// The shortest step a shortening may take (see step()) is 2⁻¹⁵ of the fixed step: at most 13 halvings of a full step
/// and the quarter after them. Measured on the UR5 drives (docs/design.md): the 1 kHz PD and computed-torque loops pass
/// at steps up to 1 ms; the excitation under continuous control, whose results are already off at 250 µs (a current
/// spike at a break-away), stops at 500 µs instead of returning nonsense (with 2⁻¹⁹ it ran through 0.06 rad off).
constexpr int kShortestStepExponent = 15;
/// Illinois iterations per located root (the bracket shrinks superlinearly; 100 ulp are met in far fewer).
constexpr int kMaxRootIterations = 100;
}  // namespace

struct FixedStepIntegrator::Impl {
  int n = 0;
  RhsFunction rhs;
  DifferenceJacobianFunction djac;
  std::function<bool()> time_invariant;  // true: fₜ = 0 (Plant::timeInvariant)
  JacobianStructure structure;
  CvodeOptions opts;
  double h = 0.0;  // the fixed step [s]
  std::unique_ptr<DirectSolver> solver;

  bool initialized = false;
  double t = kNoTime;       // time of the internal state [s]
  Eigen::VectorXd y;        // internal state
  double t_last = kNoTime;  // the time advance() last returned
  bool stepped = false;     // a step (or a located root) since initialize()
  double stop = kNoTime;    // one-shot stop time
  long step_limit = 0;      // lifetime step budget (0: none)

  // Jacobian and the factorised iteration matrix I − γ h_f W.
  Eigen::MatrixXd J;
  // With a structure: the entries a plant Jacobian may write; only these are zeroed before each one (the others stay
  // 0 from the start: 8 % of a step at 24 drives was the memset of the whole n × n).
  std::vector<EntryRun> zero_runs;
  bool jac_valid = false;
  // Oscillatory rows (setOscillatoryStates, with opts.resolve_oscillations): W with those rows scaled by
  // kOscillatoryRowScale (kept with J) and its factorisation, used on every step that is not shortened.
  std::vector<int> osc_rows;
  std::vector<char> is_osc;
  Eigen::MatrixXd Wo;
  std::unique_ptr<DirectSolver> solver_osc;
  double factored_osc_h = kNoTime;
  bool used_osc = false;  // the last step solved with solver_osc
  int steps_since_jac = 0;
  bool jac_defective = false;  // the last step's linearisation defect exceeded jacobian_defect (refresh next step)
  double factored_h = kNoTime;
  // After a step was shortened (step()): the shorter step, kept up to the end the step aimed at [s].
  double sub_h = 0.0, sub_until = kNoTime;
  // A run of shortened steps that retakes a step (step()): its length does not grow back before this time [s].
  double grow_after = kNoTime;
  double call_t0 = kNoTime;  // the time at which the current advance() call began [s]
  bool last_full = false;    // the last step was taken at its full length (not in a run of shortened steps)

  // Workspace; ft = ∂f/∂t, by a difference quotient with the Jacobian (part of W: as outdated as it).
  Eigen::VectorXd f0, f1, k1, k2, ytmp, rhs2, inc, ft;
  // The last step's cubic Hermite segment [seg_t0, seg_t1] (valid while seg_valid); seg_f1 evaluated on demand.
  bool seg_valid = false, seg_f1_valid = false;
  double seg_t0 = kNoTime, seg_t1 = kNoTime;
  Eigen::VectorXd seg_y0, seg_f0, seg_y1, seg_f1;
  // A root located beyond the last output time (the step passed both): returned by the next advance().
  bool root_pending = false;

  // Roots.
  int n_roots = 0;
  RootFunction g;
  Eigen::VectorXd g0, g1, gt;
  std::vector<int> dirs;
  bool root_found = false;

  SolverStats stats;

  std::string prefix() const {
    return "fixed-step integrator (ROS2" + (opts.component.empty() ? std::string() : ", " + opts.component) + ")";
  }

  std::string stateName(Eigen::Index i) const {
    std::string name = opts.state_name ? opts.state_name(static_cast<int>(i)) : std::string();
    return name.empty() ? "y[" + std::to_string(i) + "]" : name;
  }

  /// Calls `call` (a user callback named `what`) and turns its exceptions into a SolverError with the original nested.
  template <class F>
  void guarded(const char* what, double at, F&& call) {
    try {
      call();
    } catch (...) {
      std::string component = opts.component;
      const std::string original = callbackExceptionText(std::current_exception(), component);
      std::throw_with_nested(SolverError(prefix() + ": " + what + " threw at t = " + formatNumber(at) +
                                             " s: " + original + " [flag RHS_EXCEPTION]",
                                         at, "RHS_EXCEPTION", component));
    }
  }

  void evalRhs(double at, const Eigen::VectorXd& state, Eigen::VectorXd& out) {
    guarded("right-hand side", at, [&] { rhs(at, state, out); });
    ++stats.rhs_evals;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!std::isfinite(out[i]))
        throw SolverError(prefix() + ": the right-hand side returned a non-finite value (ydot[" + std::to_string(i) +
                              "], " + stateName(i) + ", = " + formatNumber(out[i]) + ") at t = " + formatNumber(at) +
                              " s (a fixed step cannot retry smaller: a smaller solver.step, or BDF)",
                          at, "RHS_NONFINITE", opts.component);
  }

  void evalRoots(double at, const Eigen::VectorXd& state, Eigen::VectorXd& out) {
    guarded("root function", at, [&] { g(at, state, out); });
  }

  /// The tolerance of state i at the value yi, rtol |yi| + atol_i (its error weight is the reciprocal).
  double tolerance(Eigen::Index i, double yi) const {
    return opts.rtol * std::abs(yi) + (opts.atol_vector.size() ? opts.atol_vector[i] : opts.atol);
  }

  /// W = ∂f/∂y at (t, y) with f0 = f(t, y): the plant's (difference increments as CVODE's cvLsDenseDQJac) or dense
  /// difference quotients.
  void evalJacobian(double at, const Eigen::VectorXd& state) {
    // inc_j = max(√ε |y_j|, m / w_j), w_j = 1 / (rtol |y_j| + atol_j), m = 1000 h ε n ‖f‖_w (weighted RMS norm).
    double norm = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double w = 1.0 / tolerance(i, state[i]);
      norm += (f0[i] * w) * (f0[i] * w);
    }
    norm = std::sqrt(norm / n);
    const double min_inc = norm > 0.0 ? 1000.0 * h * kEps * n * norm : 1.0;
    for (Eigen::Index j = 0; j < n; ++j)
      inc[j] = std::max(std::sqrt(kEps) * std::abs(state[j]), min_inc * tolerance(j, state[j]));
    if (djac) {
      if (zero_runs.empty()) {
        J.setZero();
      } else {
        double* d = J.data();
        for (const EntryRun& r : zero_runs) std::fill_n(d + static_cast<Eigen::Index>(r.col) * n + r.row, r.len, 0.0);
      }
      guarded("Jacobian", at, [&] { djac(at, state, f0, inc, J); });
    } else {
      ytmp = state;
      for (Eigen::Index j = 0; j < n; ++j) {
        ytmp[j] = state[j] + inc[j];
        guarded("right-hand side", at, [&] { rhs(at, ytmp, f1); });
        ++stats.rhs_evals_jacobian;
        J.col(j) = (f1 - f0) / inc[j];
        ytmp[j] = state[j];
      }
    }
    // ∂f/∂t by a forward difference over δ ≈ √ε max(|t|, h) (within the step: no sample or event lies inside it),
    // unless f does not depend on t: 0 then, which is what the difference of such an f gives bit for bit.
    if (time_invariant && time_invariant()) {
      ft.setZero();
    } else {
      const double delta = (at + std::sqrt(kEps) * std::max(std::abs(at), h)) - at;
      guarded("right-hand side", at, [&] { rhs(at + delta, state, f1); });
      ++stats.rhs_evals_jacobian;
      ft = (f1 - f0) / delta;
      for (Eigen::Index i = 0; i < n; ++i)
        if (!std::isfinite(ft[i]))
          throw SolverError(prefix() + ": the right-hand side returned a non-finite value (ydot[" + std::to_string(i) +
                                "], " + stateName(i) + ", = " + formatNumber(f1[i]) +
                                ") at t = " + formatNumber(at + delta) + " s (while differencing it in time)",
                            at + delta, "RHS_NONFINITE", opts.component);
    }
    if (!osc_rows.empty()) {
      // Wo = D·J over the entries J may hold (the structure's, or all of them), the others staying 0.
      auto copy = [&](Eigen::Index row, Eigen::Index col, Eigen::Index len) {
        for (Eigen::Index i = row; i < row + len; ++i)
          Wo(i, col) = is_osc[static_cast<size_t>(i)] ? kOscillatoryRowScale * J(i, col) : J(i, col);
      };
      if (zero_runs.empty()) {
        for (Eigen::Index j = 0; j < n; ++j) copy(0, j, n);
      } else {
        for (const EntryRun& r : zero_runs) copy(r.row, r.col, r.len);
      }
      factored_osc_h = kNoTime;
    }
    ++stats.jac_evals;
    jac_valid = true;
    steps_since_jac = 0;
    factored_h = kNoTime;
  }

  /// The relative linearisation defect of W over the first stage of a step of length hs from (t, y): with
  /// f0 = f(t, y) and f1 = f(t + hs, y + hs·k1) (the same held inputs), d = f1 − f0 − W·hs·k1 − hs·fₜ against
  /// Δf = f1 − f0, as ‖d‖_w / ‖Δf‖_w in the weights of the tolerances, w_i = 1 / (rtol |y_i| + atol_i). W exact and f
  /// linear give 0; a Jacobian that has moved along the step (a LuGre bristle that begins to slip, a gear leaving its
  /// stiffness segment) gives a defect of the order of Δf. Near an equilibrium Δf is tiny and the test renews W at
  /// most steps (a floor of 1/hs for ‖Δf‖_w, a defect below the tolerances, kept W there and let the 1 kHz PD loop of
  /// examples/ meet a LuGre break-away with it: STEP_UNSTABLE). W·hs·k1 needs no product with W: the first stage
  /// solved (I − γ·hs·W) k1 = f0 + γ·hs·fₜ, so hs·W·k1 = (k1 − f0 − γ·hs·fₜ)/γ (to the solve's rounding). W is the
  /// Jacobian: a step solved with the oscillatory rows scaled gets their W·hs·k1 back by the reciprocal scale.
  double linearisationDefect(double hs) {
    double nd = 0.0, nf = 0.0;
    const double rg = 1.0 / kGamma;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double w = 1.0 / tolerance(i, y[i]);
      const double df = f1[i] - f0[i];
      double whk = rg * (k1[i] - f0[i] - kGamma * hs * ft[i]);
      if (used_osc && is_osc[static_cast<size_t>(i)]) whk /= kOscillatoryRowScale;
      const double d = df - hs * ft[i] - whk;
      nd += (d * w) * (d * w);
      nf += (df * w) * (df * w);
    }
    if (nd == 0.0) return 0.0;
    return nf > 0.0 ? std::sqrt(nd / nf) : std::numeric_limits<double>::infinity();
  }

  /// Factorises I − γ·hs·W. A non-finite entry of W is found here, where the factorisation fails (its pivots are then
  /// not finite), instead of by a scan of every entry at each Jacobian (3 µs of a 30 µs twin step).
  void factor(double hs, double at) {
    ++stats.lin_setups;
    if (!solver->factorIdentityMinus(J, kGamma * hs)) {
      nonFiniteJacobianCheck(at);
      throw SolverError(prefix() + ": I - γhW is singular at t = " + formatNumber(at) + " s (step " + formatNumber(hs) +
                            " s)",
                        at, "LSETUP_FAIL", opts.component);
    }
    factored_h = hs;
  }

  /// Throws naming the first non-finite entry of W (the Jacobian evaluated at `at`), if there is one.
  /// With a structure, only its entries count (the others are never read).
  void nonFiniteJacobianCheck(double at) const {
    auto check = [&](Eigen::Index i, Eigen::Index j) {
      if (!std::isfinite(J(i, j)))
        throw SolverError(prefix() + ": the Jacobian has a non-finite entry J(" + std::to_string(i) + ", " +
                              std::to_string(j) + ") (" + stateName(i) + " by " + stateName(j) +
                              ") at t = " + formatNumber(at) +
                              " s: the state has left the model's range (a step too large "
                              "for the dynamics, or jacobian_every too large: smaller solver.step or BDF)",
                          at, "RHS_NONFINITE", opts.component);
    };
    if (zero_runs.empty()) {
      if (J.allFinite()) return;
      for (Eigen::Index j = 0; j < n; ++j)
        for (Eigen::Index i = 0; i < n; ++i) check(i, j);
    } else {
      for (const EntryRun& r : zero_runs)
        for (int i = 0; i < r.len; ++i) check(r.row + i, r.col);
    }
  }

  /// The error of a step that no halving lets follow an unstable mode: names the state whose own growth rate
  /// ∂fᵢ/∂yᵢ is largest (where the mode lives, as a rule: a negative damping).
  SolverError unstableStep(double hs) const {
    Eigen::Index worst = 0;
    const double rate = J.diagonal().maxCoeff(&worst);
    return SolverError(prefix() + ": the step is too large for the dynamics at t = " + formatNumber(t) +
                           " s: the linearisation has a growing mode faster than 1/(γ·" + formatNumber(hs) +
                           " s) that a fixed step cannot follow (largest growth rate ∂f/∂y = " + formatNumber(rate) +
                           " 1/s, on " + stateName(worst) +
                           "); stopped rather than return a wrong result: a smaller solver.step, or BDF",
                       t, "STEP_UNSTABLE", opts.component);
  }

  /// The shortest step a shortening may reach [s] (see step()).
  double shortest() const { return std::ldexp(h, -kShortestStepExponent); }

  /// Halves `len` while det(I − γ·probe·len·W) < 0 (W factorised at probe·len on entry); STEP_UNSTABLE when the step
  /// that would be taken (taken·len after the halving) falls below shortest().
  void halveWhileUnstable(double& len, double probe, double taken) {
    while (solver->determinantSign() < 0) {
      if (0.5 * len * taken < shortest()) throw unstableStep(probe * len);
      len *= 0.5;
      factor(probe * len, t);
    }
  }

  /// End of the next step from t: the next grid point, or the stop time before it.
  double stepEnd() const {
    const double merge = kMergeFraction * h;
    double k = std::floor(t / h) + 1.0;
    double tg = k * h;
    if (tg - t < merge) tg = (k + 1.0) * h;
    if (!std::isnan(stop) && stop > t && stop <= tg + merge) return stop;
    return tg;
  }

  /// One ROS2 step from (t, y) towards t1, or a shorter one (see below); fills the Hermite segment.
  ///
  /// A step that cannot follow an instability is shortened. ROS2's stability function R(z) = (1 + (1 − 2γ)z)/(1 − γz)²
  /// is below 1 in magnitude for real z = hλ > 1.6, so a long step damps a mode that grows (λ > 0) instead of
  /// following it. On the UR5 drives such modes are the LuGre friction's negative damping: where the bristle
  /// deflection passes its steady state (σ₀z > g), ∂ż/∂v = 1 − σ₀z/g < 0 and the σ₁ż term of the friction torque
  /// acts on a wrist joint's small inertia as a damping σ₁(1 − σ₀z/g) < 0, with λ measured from 5e3 to 2e7 1/s for
  /// a few tens of µs at a break-away. Damping them held a wrist joint at its start for good at h = 100 µs (a wrong
  /// result with no error; docs/design.md). det(I − γhW) = Π(1 − γhλᵢ) over W's eigenvalues is negative exactly
  /// when an odd number of them are real with γhλ > 1 (a complex pair contributes |1 − γhλ|² > 0), and the
  /// factorisation gives its sign for nothing. Such a step is halved (same W) until the sign is positive, then
  /// quartered (γhλ < 1 only moves the step below R's pole: R(0.5) = −9.7 against e^0.5 = 1.65; a quarter of it puts
  /// hλ below 0.15, where R follows e^{hλ} to 1 %), and the sign is checked again (a second growing mode can make
  /// it positive while the first is still too fast). The steps after it keep that length up to the end the first
  /// shortened step aimed at (the grid point, or a stop time), each checked again and shortened again if need be;
  /// each also factors W at 8× its length, and a positive sign there (the growth has slowed 8×, or ended) doubles
  /// the length, so a break-away of tens of µs does not leave the rest of a long control period in nanosecond steps.
  /// A remainder to the aim shorter than the step length is taken as it is (shorter: safe). When the step before was
  /// a full one and nothing of it has been returned, it is retaken with the shorter steps (see below). A mode that
  /// would need steps below 2⁻¹⁵ of the fixed step is an error. Not caught: steps with 0.15 < hλ < 0.59 outside
  /// such runs (|R| > 1, but not e^{hλ}), an even number of too-fast growing modes, unstable complex pairs, and a W
  /// too old to show them (jacobian_every > 1).
  void step(double t1) {
    const double merge = kMergeFraction * h;
    evalRhs(t, y, f0);
    if (!jac_valid || steps_since_jac >= opts.jacobian_every || jac_defective) evalJacobian(t, y);
    jac_defective = false;
    double aim = t1;  // where a run of shortened steps (this one, or one begun before) ends
    if (sub_h > 0.0) {
      if (t >= sub_until - merge) {
        sub_h = 0.0;
      } else {
        aim = std::min(t1, sub_until);
        // Each step of the run keeps det(I − 4γsW) > 0 (hλ < 0.15, as the first); one at 8× the length allows 2×
        // (not while retaking a step, before the time where the mode was found).
        bool grown = false;
        if (!(t < grow_after - merge)) {
          factor(8.0 * sub_h, t);
          grown = solver->determinantSign() > 0;
        }
        if (grown) {
          sub_h *= 2.0;
        } else {
          factor(4.0 * sub_h, t);
          if (solver->determinantSign() < 0) ++stats.split_steps;
          halveWhileUnstable(sub_h, 4.0, 1.0);
        }
        // (the last one ends where the shortened steps aimed: no rounding remainder)
        t1 = aim - t > sub_h + merge ? t + sub_h : aim;
      }
    }
    double hs = t1 - t;
    // (A factorisation at a length within 1e-9 of hs is kept: the grid's rounding moves hs in its last bits, and
    // I − γ·hs(1 + δ)·W is I − γ·hs·W' with W' = (1 + δ)W, as good a W for a W-method.)
    if (!(std::abs(factored_h - hs) <= 1e-9 * hs)) factor(hs, t);
    if (solver->determinantSign() < 0) {
      halveWhileUnstable(hs, 1.0, 0.25);
      hs *= 0.25;
      factor(hs, t);
      halveWhileUnstable(hs, 1.0, 1.0);
      sub_h = hs;
      sub_until = aim;
      ++stats.split_steps;
      // The full step before this one ended here, inside the growing region, which the linearisation at its start
      // could not show: it overshot (at 250 µs on the UR5 excitation a wrist current 3× its range off for a sample).
      // When nothing of it has been returned yet (it was taken in this advance() call, which returns only at its end)
      // and it was longer than the length found here, it is retaken from its start with that length, which does not
      // grow back before here. (The discarded step stays counted in the steps and the step budget.)
      if (last_full && seg_valid && seg_t1 == t && !(seg_t0 < call_t0) && seg_t1 - seg_t0 > hs) {
        grow_after = t;
        t = seg_t0;
        y = seg_y0;
        if (n_roots > 0) evalRoots(t, y, g0);
        f0 = seg_f0;  // (the right-hand side there, as the discarded step evaluated it)
        evalJacobian(t, y);
        factor(hs, t);
        halveWhileUnstable(hs, 1.0, 1.0);
        sub_h = hs;
        ++stats.retaken_steps;
      }
      t1 = t + hs;
    }
    // [Verwer1999, eq. 2.2] with W and ∂f/∂t from the last Jacobian evaluation; with oscillatory rows, W with those
    // rows scaled unless the step was shortened (the shortenings' analysis and the growing modes are γ = 1 + 1/√2's).
    DirectSolver* w_solver = solver.get();
    used_osc = !osc_rows.empty() && sub_h == 0.0;
    if (used_osc) {
      if (!(std::abs(factored_osc_h - hs) <= 1e-9 * hs)) {
        ++stats.lin_setups;
        if (!solver_osc->factorIdentityMinus(Wo, kGamma * hs))
          throw SolverError(prefix() + ": I - γhW with the oscillatory rows scaled is singular at t = " +
                                formatNumber(t) + " s (step " + formatNumber(hs) + " s)",
                            t, "LSETUP_FAIL", opts.component);
        factored_osc_h = hs;
      }
      // The scaled matrix's own determinant: a real eigenvalue of D·W with γhμ > 1 that W does not have (a mode
      // shared by scaled and unscaled rows) would put the step next to R's pole; such a step is taken with W.
      if (solver_osc->determinantSign() > 0) {
        w_solver = solver_osc.get();
      } else {
        used_osc = false;
        ++stats.damped_steps;
      }
    }
    rhs2 = f0 + (kGamma * hs) * ft;
    w_solver->solve(rhs2, k1);
    ytmp = y + hs * k1;
    evalRhs(t1, ytmp, f1);
    if (opts.jacobian_defect > 0.0 && linearisationDefect(hs) > opts.jacobian_defect) jac_defective = true;
    rhs2 = f1 - 2.0 * k1 - (kGamma * hs) * ft;
    w_solver->solve(rhs2, k2);
    seg_t0 = t;
    seg_y0 = y;
    seg_f0 = f0;
    seg_t1 = t1;
    y += (1.5 * hs) * k1 + (0.5 * hs) * k2;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!std::isfinite(y[i]))
        throw SolverError(prefix() + ": the state became non-finite (" + stateName(i) +
                              ") in the step to t = " + formatNumber(t1) + " s",
                          t1, "RHS_NONFINITE", opts.component);
    seg_y1 = y;
    seg_valid = true;
    seg_f1_valid = false;
    last_full = sub_h == 0.0;
    t = t1;
    stepped = true;
    ++steps_since_jac;
    ++stats.steps;
    stats.last_step = hs;
    stats.last_order = 2;
  }

  /// The cubic Hermite interpolant of the last step at time `at` into `out`.
  void interpolate(double at, Eigen::VectorXd& out) {
    if (!seg_f1_valid) {
      evalRhs(seg_t1, seg_y1, seg_f1);
      seg_f1_valid = true;
    }
    const double hs = seg_t1 - seg_t0;
    const double s = (at - seg_t0) / hs;
    const double s2 = s * s, s3 = s2 * s;
    const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
    out = h00 * seg_y0 + (h10 * hs) * seg_f0 + h01 * seg_y1 + (h11 * hs) * seg_f1;
  }

  /// After a step: the earliest sign change of the root functions over it, located on the interpolant; the state
  /// moved back there (the step beyond is dropped). False when none changed sign.
  bool locateRoot() {
    if (n_roots == 0) return false;
    evalRoots(t, y, g1);
    bool any = false;
    for (int i = 0; i < n_roots; ++i) {
      const double a = g0[i], b = g1[i];
      if (a != 0.0 && (b == 0.0 || (a < 0.0) != (b < 0.0))) any = true;
    }
    if (!any) {
      g0 = g1;
      return false;
    }
    const double ta = seg_t0, tb = seg_t1;
    const double tol = 100.0 * kEps * (std::abs(tb) + (tb - ta));
    double t_root = tb;
    for (int i = 0; i < n_roots; ++i) {
      double ga = g0[i], gb = g1[i];
      if (!(ga != 0.0 && (gb == 0.0 || (ga < 0.0) != (gb < 0.0)))) continue;
      // Illinois on [lo, hi] with g_i(lo) of the start's sign; hi ends past (or on) the root.
      double lo = ta, hi = std::min(tb, t_root);
      if (hi < tb) {  // an earlier root of another function bounds this one's search
        interpolate(hi, ytmp);
        evalRoots(hi, ytmp, gt);
        gb = gt[i];
        if (!(gb == 0.0 || (ga < 0.0) != (gb < 0.0))) continue;
      }
      int side = 0;
      for (int it = 0; it < kMaxRootIterations && hi - lo > tol; ++it) {
        double tm = hi - gb * (hi - lo) / (gb - ga);
        if (!(tm > lo && tm < hi)) tm = 0.5 * (lo + hi);
        interpolate(tm, ytmp);
        evalRoots(tm, ytmp, gt);
        const double gm = gt[i];
        if (gm == 0.0 || (ga < 0.0) != (gm < 0.0)) {
          hi = tm;
          gb = gm;
          if (side == 1) ga *= 0.5;
          side = 1;
        } else {
          lo = tm;
          ga = gm;
          if (side == -1) gb *= 0.5;
          side = -1;
        }
      }
      t_root = std::min(t_root, hi);
    }
    // The state at the root; every function whose sign differs there from the step's start fired.
    if (t_root < tb) {
      interpolate(t_root, ytmp);
      y = ytmp;
    }
    evalRoots(t_root, y, gt);
    for (int i = 0; i < n_roots; ++i) {
      const double a = g0[i], b = gt[i];
      dirs[static_cast<size_t>(i)] = (a != 0.0 && (b == 0.0 || (a < 0.0) != (b < 0.0))) ? (a < 0.0 ? 1 : -1) : 0;
    }
    t = t_root;  // the segment's cubic still interpolates [seg_t0, t_root]
    g0 = gt;
    return true;
  }
};

FixedStepIntegrator::FixedStepIntegrator(int n, RhsFunction rhs, CvodeOptions options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.opts = std::move(options);
  auto bad = [&](const std::string& what) { throw InputError(m.prefix() + ": " + what); };
  if (n <= 0) bad("the number of states must be > 0, got " + std::to_string(n));
  if (!rhs) bad("no right-hand side given");
  if (m.opts.method != Method::Rosenbrock) bad("the options must select Method::Rosenbrock");
  if (!(m.opts.fixed_step > 0.0) || !std::isfinite(m.opts.fixed_step))
    bad("fixed_step must be a finite step > 0 s, got " + formatNumber(m.opts.fixed_step));
  if (m.opts.jacobian_every < 1) bad("jacobian_every must be >= 1 step, got " + std::to_string(m.opts.jacobian_every));
  if (!(m.opts.jacobian_defect >= 0.0) || !std::isfinite(m.opts.jacobian_defect))
    bad("jacobian_defect must be finite and >= 0 (0: off), got " + formatNumber(m.opts.jacobian_defect));
  if (m.opts.resolve_oscillations) {
    if (m.opts.jacobian_defect > kResolveMaxJacobianDefect)
      bad("with oscillations resolved (rows taken with γ = 1 − 1/√2, which tolerate a Jacobian off by 17 %) "
          "jacobian_defect must be at most " +
          formatNumber(kResolveMaxJacobianDefect) + ", got " + formatNumber(m.opts.jacobian_defect) +
          " (jacobian_every: adaptive gives " + formatNumber(kResolveJacobianDefect) + ")");
    if (m.opts.jacobian_every > 1 && m.opts.jacobian_defect == 0.0)
      bad("with oscillations resolved a Jacobian kept for " + std::to_string(m.opts.jacobian_every) +
          " steps without the defect test diverges: jacobian_every 1 or adaptive");
  }
  if (m.opts.max_num_steps <= 0) bad("max_num_steps must be > 0, got " + std::to_string(m.opts.max_num_steps));
  if (!(m.opts.rtol > 0.0) || !std::isfinite(m.opts.rtol)) bad("rtol must be finite and > 0");
  if (m.opts.atol_vector.size() != 0 && m.opts.atol_vector.size() != n)
    bad("atol_vector has " + std::to_string(m.opts.atol_vector.size()) + " entries, expected " + std::to_string(n));
  m.n = n;
  m.h = m.opts.fixed_step;
  m.rhs = std::move(rhs);
  m.J.setZero(n, n);
  for (Eigen::VectorXd* v :
       {&m.f0, &m.f1, &m.k1, &m.k2, &m.ytmp, &m.rhs2, &m.inc, &m.seg_y0, &m.seg_f0, &m.seg_y1, &m.seg_f1, &m.y, &m.ft})
    v->setZero(n);
  m.solver = std::make_unique<DirectSolver>(n, m.structure);
  if (m.opts.jacobian_defect > 0.0) m.solver->useExplicitInverses();  // a kept W serves many solves
  m.is_osc.assign(static_cast<size_t>(n), 0);
}

FixedStepIntegrator::~FixedStepIntegrator() = default;

void FixedStepIntegrator::initialize(double t0, const Eigen::Ref<const Eigen::VectorXd>& y0, bool reuse_jacobian) {
  Impl& m = *impl_;
  if (y0.size() != m.n)
    throw InputError(m.prefix() + ": initialize: the state has " + std::to_string(y0.size()) + " entries, expected " +
                     std::to_string(m.n));
  if (!std::isfinite(t0) || !y0.allFinite()) throw InputError(m.prefix() + ": initialize: t0 and y0 must be finite");
  m.t = m.t_last = t0;
  m.y = y0;
  m.initialized = true;
  m.stepped = m.seg_valid = m.root_pending = m.root_found = false;
  m.sub_h = 0.0;
  m.last_full = false;
  m.grow_after = kNoTime;
  if (!reuse_jacobian) {
    m.jac_valid = false;
    m.jac_defective = false;
  }  // (a kept Jacobian keeps its verdict: under input_jumps: restart every sample restarts)
  if (m.n_roots > 0) {
    m.evalRoots(t0, m.y, m.g0);
    std::fill(m.dirs.begin(), m.dirs.end(), 0);
  }
}

double FixedStepIntegrator::advance(double t_out, Eigen::Ref<Eigen::VectorXd> y_out) {
  Impl& m = *impl_;
  if (!m.initialized) throw Error(m.prefix() + ": advance before initialize");
  if (y_out.size() != m.n)
    throw InputError(m.prefix() + ": advance: the output has " + std::to_string(y_out.size()) + " entries, expected " +
                     std::to_string(m.n));
  if (!std::isfinite(t_out)) throw InputError(m.prefix() + ": advance: t_out must be finite");
  m.root_found = false;
  std::fill(m.dirs.begin(), m.dirs.end(), 0);
  auto at = [&](double when) {                          // y(when) on the last segment (when <= m.t)
    if (std::abs(when - m.t) < kMergeFraction * m.h) {  // (or a time this close: rounding)
      y_out = m.y;
    } else {
      m.interpolate(when, m.ytmp);
      y_out = m.ytmp;
    }
    m.t_last = when;
    return when;
  };
  if (m.root_pending) {
    if (t_out < m.t) return at(t_out);
    m.root_pending = false;
    m.root_found = true;
    return at(m.t);
  }
  if (t_out <= m.t) {
    if (t_out == m.t || (m.seg_valid && t_out >= m.seg_t0)) return at(t_out);
    throw InputError(m.prefix() + ": advance: t_out = " + formatNumber(t_out) +
                     " s lies before the last step (t = " + formatNumber(m.t) + " s)");
  }
  long here = 0;
  m.call_t0 = m.t;
  while (m.t < t_out) {
    if (!std::isnan(m.stop) && m.t >= m.stop) break;
    if (++here > m.opts.max_num_steps)
      throw SolverError(m.prefix() + ": " + std::to_string(m.opts.max_num_steps) +
                            " steps (max_num_steps) in one call before t = " + formatNumber(t_out) + " s",
                        m.t, "CV_TOO_MUCH_WORK", m.opts.component);
    if (m.step_limit > 0 && m.stats.steps >= m.step_limit) {
      ++m.stats.steps;
      throw SolverError(m.prefix() + ": the step budget of " + std::to_string(m.step_limit) +
                            " steps is spent at t = " + formatNumber(m.t) + " s",
                        m.t, "STEP_BUDGET", m.opts.component);
    }
    if (!std::isnan(m.stop) && m.stop - m.t < kMergeFraction * m.h) {
      // A stop this close (rounding of the caller's times against the grid) is where the state already is.
      m.t = m.stop;
      break;
    }
    const double t1 = m.stepEnd();
    m.step(t1);
    if (m.locateRoot()) {
      if (m.t <= t_out) {
        m.root_found = true;
        if (m.t == m.stop) m.stop = kNoTime;
        return at(m.t);
      }
      m.root_pending = true;
      return at(t_out);
    }
  }
  if (!std::isnan(m.stop) && m.t == m.stop && m.stop <= t_out) {
    m.stop = kNoTime;
    return at(m.t);
  }
  return at(std::min(t_out, m.t));
}

void FixedStepIntegrator::setStopTime(double t_stop) {
  Impl& m = *impl_;
  if (!std::isfinite(t_stop)) throw InputError(m.prefix() + ": setStopTime: the stop time must be finite");
  if (m.initialized && t_stop < m.t)
    throw InputError(m.prefix() + ": setStopTime: " + formatNumber(t_stop) +
                     " s lies behind the last step (t = " + formatNumber(m.t) + " s)");
  m.stop = t_stop;
}

void FixedStepIntegrator::setStepLimit(long steps) {
  if (steps < 0) throw InputError(impl_->prefix() + ": setStepLimit: expected a number of steps >= 0");
  impl_->step_limit = steps;
}

void FixedStepIntegrator::setDifferenceJacobian(DifferenceJacobianFunction jacobian) {
  impl_->djac = std::move(jacobian);
  impl_->jac_valid = false;
}

void FixedStepIntegrator::setTimeInvariance(std::function<bool()> invariant) {
  impl_->time_invariant = std::move(invariant);
}

void FixedStepIntegrator::setOscillatoryStates(std::vector<int> states) {
  Impl& m = *impl_;
  std::sort(states.begin(), states.end());
  for (size_t k = 0; k < states.size(); ++k)
    if (states[k] < 0 || states[k] >= m.n || (k > 0 && states[k] == states[k - 1]))
      throw InputError(m.prefix() + ": setOscillatoryStates: state " + std::to_string(states[k]) +
                       (states[k] < 0 || states[k] >= m.n ? " is not one of the " + std::to_string(m.n) + " states"
                                                          : " is given twice"));
  if (m.opts.resolve_oscillations && states.empty())
    throw InputError(m.prefix() + ": oscillations: resolve, but the model declares no oscillatory states "
                                  "(Plant::oscillatoryStates: the robot with drives does; other models only damp)");
  if (!m.opts.resolve_oscillations) states.clear();
  m.osc_rows = std::move(states);
  m.is_osc.assign(static_cast<size_t>(m.n), 0);
  for (int i : m.osc_rows) m.is_osc[static_cast<size_t>(i)] = 1;
  m.solver_osc.reset();
  if (!m.osc_rows.empty()) {
    m.solver_osc = std::make_unique<DirectSolver>(m.n, m.structure);
    if (m.opts.jacobian_defect > 0.0) m.solver_osc->useExplicitInverses();
    m.Wo.setZero(m.n, m.n);
  }
  m.jac_valid = false;
  m.factored_osc_h = kNoTime;
}

void FixedStepIntegrator::setJacobianStructure(JacobianStructure structure) {
  Impl& m = *impl_;
  structure.validate(m.n);
  m.structure = std::move(structure);
  m.solver = std::make_unique<DirectSolver>(m.n, m.structure);
  if (m.opts.jacobian_defect > 0.0) m.solver->useExplicitInverses();
  m.factored_h = kNoTime;
  if (m.solver_osc) {
    m.solver_osc = std::make_unique<DirectSolver>(m.n, m.structure);
    if (m.opts.jacobian_defect > 0.0) m.solver_osc->useExplicitInverses();
    m.factored_osc_h = kNoTime;
  }
  m.zero_runs = structureRuns(m.structure, m.n);
}

double FixedStepIntegrator::jumpError(const Eigen::Ref<const Eigen::VectorXd>&,
                                      const Eigen::Ref<const Eigen::VectorXd>&, double) const {
  return 0.0;
}

void FixedStepIntegrator::setRootFunction(int n_roots, RootFunction g) {
  Impl& m = *impl_;
  if (n_roots < 0 || (n_roots > 0 && !g)) throw InputError(m.prefix() + ": setRootFunction: bad root functions");
  m.n_roots = n_roots;
  m.g = std::move(g);
  m.g0.setZero(n_roots);
  m.g1.setZero(n_roots);
  m.gt.setZero(n_roots);
  m.dirs.assign(static_cast<size_t>(n_roots), 0);
}

bool FixedStepIntegrator::rootFound() const { return impl_->root_found; }
const std::vector<int>& FixedStepIntegrator::rootDirections() const { return impl_->dirs; }

double FixedStepIntegrator::lastStep(Eigen::Ref<Eigen::VectorXd> y) const {
  const Impl& m = *impl_;
  if (!m.stepped || y.size() != m.n) return kNoTime;
  y = m.y;
  return m.t;
}

double FixedStepIntegrator::time() const { return impl_->t_last; }

SolverStats FixedStepIntegrator::stats() const {
  SolverStats s = impl_->stats;
  s.current_time = impl_->t;
  return s;
}

long FixedStepIntegrator::steps() const { return impl_->stats.steps; }
const CvodeOptions& FixedStepIntegrator::options() const { return impl_->opts; }

}  // namespace jointsim::sim
