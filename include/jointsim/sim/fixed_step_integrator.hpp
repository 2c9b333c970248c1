#pragma once
/// \file
/// The fixed-step integrator of sampled control (CvodeOptions::method = Method::Rosenbrock): the two-stage
/// Rosenbrock-W method ROS2 of [Verwer1999] on a grid locked to the control clock,
///
///   (I − γhW) k₁ = f(tₙ, yₙ) + γh fₜ,
///   (I − γhW) k₂ = f(tₙ + h, yₙ + h k₁) − 2 k₁ − γh fₜ,
///   yₙ₊₁ = yₙ + (3/2) h k₁ + (1/2) h k₂,          γ = 1 + 1/√2,
///
/// with W ≈ ∂f/∂y (the plant's Jacobian or difference quotients) and fₜ ≈ ∂f/∂t (a difference quotient), both
/// refreshed every CvodeOptions::jacobian_every steps. ROS2 is of order 2 for any W and fₜ (a W-method; t counts as a
/// state whose Jacobian column is fₜ) and L-stable with the exact Jacobian, so a lightly damped gear mode above the
/// step's Nyquist frequency is damped, not resolved (docs/design.md, "Fixed-step integration"). fₜ matters where a stiff
/// part is forced by time (a fast loop tracking a moving reference): without it such a component is followed to first
/// order only. A step costs two right-hand sides and two solves with one factorisation of I − γhW (block elimination
/// with the plant's JacobianStructure), plus a Jacobian and one more right-hand side (fₜ; none for a right-hand side
/// declared time invariant, setTimeInvariance: a plant under sampled control) when they are refreshed; there is
/// no error estimate, no error-controlled step rejection and no nonlinear iteration that could fail.
///
/// A step whose linearisation has a growing real mode it would damp instead of follow (det(I − γhW) < 0: γhλ > 1) is
/// shortened — halved until the sign is positive, then quartered, the following steps up to the grid point checked at
/// 4× and grown back at 8× their length — and counted in SolverStats::split_steps; the full step before it, which ran
/// into the mode unseen, is retaken with the shorter steps when nothing of it was returned yet
/// (SolverStats::retaken_steps). A mode that needs steps below 2⁻¹⁵ of the fixed step stops the run (STEP_UNSTABLE).
/// docs/design.md, "Growing modes", has the measurements on the UR5 drives' LuGre break-aways that made this
/// necessary, and what it does not catch.
///
/// With CvodeOptions::resolve_oscillations the rows of the plant's oscillatory states (setOscillatoryStates) are taken
/// with ROS2's other L-stable γ, 1 − 1/√2: W's rows scaled by (1 − 1/√2)/(1 + 1/√2), factorised beside I − γhW
/// (whose determinant still decides the shortenings; a shortened step uses it alone). The linearisation defect is
/// measured against the Jacobian itself.
///
/// Steps end on the grid k·fixed_step (k integer). A stop time between two grid points (a time event) ends a short
/// step on it, after which the grid is met again. Root functions are checked at the end of every step; a sign change
/// is located on the step's cubic Hermite interpolant (from yₙ, f(tₙ, yₙ), yₙ₊₁, f(tₙ₊₁, yₙ₊₁)) by the Illinois
/// method to 100 ulp of the time, and the integrator returns there, as CVODE does. A root function that is exactly 0
/// at the start of a step (just after an event) takes its sign from the end of that step. Outputs between two steps
/// are interpolated on the same cubic (third-order accurate).
///
/// Not copyable. Not thread-safe; distinct instances are independent.

#include <memory>

#include "jointsim/sim/cvode_integrator.hpp"

namespace jointsim::sim {

class FixedStepIntegrator final : public Integrator {
 public:
  /// \param n        number of states (> 0)
  /// \param rhs      right-hand side (non-empty)
  /// \param options  method Method::Rosenbrock, fixed_step > 0 [s], jacobian_every >= 1, max_num_steps > 0;
  ///                 rtol and atol only scale the difference increments of a Jacobian by differences (as CVODE's)
  /// \throws InputError on invalid arguments/options
  FixedStepIntegrator(int n, RhsFunction rhs, CvodeOptions options);
  ~FixedStepIntegrator() override;
  FixedStepIntegrator(const FixedStepIntegrator&) = delete;
  FixedStepIntegrator& operator=(const FixedStepIntegrator&) = delete;

  /// (t0, y0) [s, state units]; reuse_jacobian keeps the last Jacobian (an input jump), else a fresh one is evaluated
  /// at the next step.
  void initialize(double t0, const Eigen::Ref<const Eigen::VectorXd>& y0, bool reuse_jacobian) override;
  /// Steps up to t_out [s] (or a root, or the stop time before it) and writes y(t) into y_out; returns that time. The
  /// last step may pass t_out (unless a stop time is set there): y(t_out) is then interpolated.
  /// \throws SolverError (time, component) on a non-finite right-hand side or state, a singular I − γhW, a growing mode
  /// no shortened step follows (STEP_UNSTABLE), an exception
  /// of a callback (flag RHS_EXCEPTION, the original nested), max_num_steps steps in one call (CV_TOO_MUCH_WORK) or the
  /// step budget (STEP_BUDGET).
  double advance(double t_out, Eigen::Ref<Eigen::VectorXd> y_out) override;
  void setStopTime(double t_stop) override;
  void setStepLimit(long steps) override;
  void setDifferenceJacobian(DifferenceJacobianFunction jacobian) override;
  void setJacobianStructure(JacobianStructure structure) override;
  /// While `invariant()` is true, fₜ = 0 without the difference in time (its right-hand side is saved).
  void setTimeInvariance(std::function<bool()> invariant) override;
  /// The rows taken with γ = 1 − 1/√2 under CvodeOptions::resolve_oscillations (ignored without); InputError for an
  /// index outside 0..n−1 or given twice.
  void setOscillatoryStates(std::vector<int> states) override;
  /// 0: a fixed-step method carries no history across an input jump (the next step starts from f with the new inputs).
  double jumpError(const Eigen::Ref<const Eigen::VectorXd>& f_old, const Eigen::Ref<const Eigen::VectorXd>& f_new,
                   double h_max) const override;
  bool jumpErrorIsZero() const override { return true; }
  void setRootFunction(int n_roots, RootFunction g) override;
  bool rootFound() const override;
  const std::vector<int>& rootDirections() const override;
  double lastStep(Eigen::Ref<Eigen::VectorXd> y) const override;
  double time() const override;
  /// steps, rhs_evals, rhs_evals_jacobian, jac_evals, lin_setups (factorisations), last_order (2), last_step,
  /// current_time; no error-test or convergence failures can occur.
  SolverStats stats() const override;
  long steps() const override;
  const CvodeOptions& options() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace jointsim::sim
