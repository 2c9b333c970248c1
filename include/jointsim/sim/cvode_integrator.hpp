#pragma once
/// \file
/// RAII wrapper around the SUNDIALS CVODE integrator (SUNDIALS 6.x) for explicit ODE systems
/// y' = f(t, y) with y in R^n.
///
/// The SUNDIALS types are hidden behind a pimpl: this header only needs Eigen and the standard
/// library. Every CVODE failure is reported as a jointsim::SolverError carrying the simulated time,
/// the CVODE flag name, the component involved and CVODE's own diagnostic text (CVODE never prints
/// to stderr through this wrapper). Misuse that can be detected up front (bad sizes, bad options)
/// is reported as a jointsim::InputError.

#include <Eigen/Core>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace jointsim::sim {

/// Linear multistep family used by CVODE.
enum class Method {
  /// Backward differentiation formulas (orders 1..5) solved with Newton iteration and a dense direct
  /// linear solver. The choice for stiff systems (joint friction, contact, stiff drives).
  BDF,
  /// Adams-Moulton formulas (orders 1..12) solved with fixed-point (functional) iteration; no linear
  /// solver, no Jacobian. Cheaper per step for non-stiff systems, but fails or crawls on stiff ones.
  Adams,
  /// Not CVODE: the fixed-step, linearly implicit two-stage Rosenbrock-W method ROS2 of [Verwer1999]
  /// (sim::FixedStepIntegrator; order 2 with any Jacobian approximation, L-stable) on a grid of CvodeOptions::fixed_step
  /// locked to the control clock: no error control, no step rejection, two right-hand sides and two linear solves per
  /// step. For sampled control where wall time per control period matters (docs/design.md, "Fixed-step integration").
  Rosenbrock,
};

/// Block structure of the Jacobian ∂f/∂y of a system made of a hub (e.g. a multibody's q, q̇) and parts that
/// couple only to themselves and to the hub (e.g. one drive per joint): J(i, j) = 0 whenever i and j lie in two
/// different blocks. The BDF Newton matrix I − γJ then has a bordered block-diagonal form, which
/// CvodeIntegrator factorises by block elimination (each block's LU, then the hub's Schur complement), in
/// O(Σ m_k³ + h³) instead of O(n³). Every state lies in the hub or in exactly one block.
struct JacobianStructure {
  std::vector<int> hub;                  ///< states coupled to every other state
  std::vector<std::vector<int>> blocks;  ///< groups coupled only to themselves and to the hub
  /// Optional (empty: every hub state), one list per block: the hub states the block's rows may depend on (the
  /// Jacobian's entries of the block's rows are zero in every other hub column).
  std::vector<std::vector<int>> block_hub_columns{};
  /// Optional (empty: every hub state), one list per block: the hub states whose rows may depend on the block's
  /// states (the entries of the block's columns are zero in every other hub row). With both, the block elimination
  /// reads and updates only these entries: a drive that reads its own joint's angle and rate and acts on the
  /// accelerations costs O(n) of the hub, not O(n²).
  std::vector<std::vector<int>> block_hub_rows{};
  bool empty() const { return blocks.empty(); }
  /// InputError unless every index 0..n−1 appears exactly once, and the optional lists (one per block) name hub
  /// states, each once.
  void validate(int n) const;
};

/// Integrator settings. Validated by the CvodeIntegrator constructor (InputError on bad values).
struct CvodeOptions {
  /// Integration method, see Method.
  Method method = Method::BDF;
  /// Relative tolerance [-], > 0. CVODE keeps the local error of each component below
  /// rtol * |y_i| + atol_i.
  double rtol = 1e-6;
  /// Scalar absolute tolerance, >= 0, in the units of the state components. Used for every
  /// component when atol_vector is empty.
  double atol = 1e-8;
  /// Per-component absolute tolerances (size n, every entry >= 0, in the units of the matching
  /// state component). Overrides atol when non-empty.
  Eigen::VectorXd atol_vector;
  /// Upper bound on |step size| [s], >= 0; 0 means unlimited.
  double max_step = 0.0;
  /// First step size to try [s]; 0 lets CVODE estimate it. Its sign must match the direction of
  /// integration.
  double initial_step = 0.0;
  /// Lower bound on |step size| [s], >= 0 (and <= max_step when max_step > 0); 0 means no bound.
  double min_step = 0.0;
  /// Maximum number of internal steps per call of advance(), > 0. Exceeding it raises a
  /// SolverError with flag "CV_TOO_MUCH_WORK"; the integrator remains usable and a further
  /// advance() continues from where it stopped.
  long max_num_steps = 500000;
  /// Maximum method order; 0 means CVODE's default (5 for BDF, 12 for Adams). Otherwise
  /// 1..5 for BDF, 1..12 for Adams.
  int max_order = 0;
  /// Relative change of γ = h·β₀ (step size times the BDF coefficient) beyond which CVODE forms and factorises a new
  /// Newton matrix I − γJ (CVodeSetDeltaGammaMaxLSetup; CVODE's default 0.3), > 0. BDF only. Under sampled control
  /// every stop at a sample shortens a step and every restart starts small, so γ changes often; 0.5 saved a
  /// quarter of the factorisations of the UR5 PD loop at equal steps (examples/pd_voltage_ur5.cpp); a larger value
  /// makes the Newton iteration slower to converge where the step changes a lot.
  double max_gamma_change = 0.3;
  /// Enable BDF stability limit detection (CVodeSetStabLimDet). BDF of order >= 3 is not A-stable:
  /// for lightly damped oscillatory modes (eigenvalues near the imaginary axis) it can be forced to
  /// tiny steps or go unstable; the detection lowers the order when it sees this. Only valid with
  /// Method::BDF (InputError with Adams).
  bool stability_limit_detection = false;
  /// Dense direct solver of the BDF Newton systems: Eigen's blocked, vectorised partial-pivoting LU
  /// (default; several times faster than SUNDIALS' reference loops for tens of states) or SUNDIALS'
  /// own SUNLinSol_Dense. Both solve the same systems to rounding.
  enum class DenseSolver { Eigen, Sundials } dense_solver = DenseSolver::Eigen;
  /// Check every derivative and Jacobian for NaN/Inf entries. A non-finite result is reported to
  /// CVODE as a recoverable failure (it retries with a smaller step, which helps when an oversized
  /// trial step left the physical range); see max_nonfinite_retries. The resulting SolverError names
  /// the offending entry (ydot[i] or J(i, j)) and time. Costs one pass over ydot (and J) per
  /// evaluation. When false, NaNs reach CVODE unchecked (typically error-test or convergence failures).
  bool check_finite = true;
  /// Number of non-finite results tolerated (as recoverable) per advance() call, >= 0. The next one
  /// is unrecoverable and advance() fails promptly, typically with CV_RHSFUNC_FAIL (at the first
  /// evaluation: CV_FIRST_RHSFUNC_ERR; repeated failures on one step: CV_REPTD_RHSFUNC_ERR; Jacobian:
  /// CV_LSETUP_FAIL). Without this budget, an RHS that is NaN for all t beyond some time makes CVODE
  /// creep towards that time until max_num_steps is spent. 0 = every non-finite result is fatal.
  int max_nonfinite_retries = 100;
  /// How sim::simulate and sim::Simulator go on where a held input jumps: at the samples of a sampled (zero-order
  /// hold) controller and where an input set between steps changes (PlantState::inputRevision). The state is continuous
  /// there; only its derivative jumps.
  /// - `KeepHistory` (default): where the jump is small, h‖Δẏ‖_w ≤ 1 (CvodeIntegrator::jumpError: the next step
  ///   then passes the error test), the integrator stops exactly at the jump (a stop time) and continues with its
  ///   step size, order and Newton matrix; the local error test still measures the mismatch with the history.
  ///   Larger jumps restart, as under `Restart` (carrying the history through them makes CVODE fail its error
  ///   test down to the minimum step).
  /// - `Restart`: CVodeReInit at every jump (order 1, a fresh step-size estimate, a new Jacobian): the reference
  ///   the default is tested against; costs several steps per jump on a stiff drive train.
  /// Root events, time events (profile and trajectory breakpoints) and state changes (setState, a bumpless port
  /// switch) always restart. CvodeIntegrator itself does not read this setting.
  enum class InputJump { KeepHistory, Restart } input_jump = InputJump::KeepHistory;
  /// Use the plant's own Jacobian and block structure where it provides them (sim::Plant::providesJacobian; read
  /// by sim::simulate and sim::Simulator). false: CVODE's dense difference quotients, one RHS evaluation per
  /// state, and a dense LU (the reference the structured Jacobian is tested against).
  bool plant_jacobian = true;
  /// Name of the simulated system, used in error messages (e.g. "ur5 multibody"). May be empty.
  std::string component;
  /// Name of state component i for messages (e.g. "elbow_joint.i_motor"); sim::simulate and sim::Simulator give the
  /// plant's (Plant::stateName). A failure names the state with the largest weighted local error of the last step:
  /// the part of the model that limited the step. Empty names are shown as "y[i]".
  std::function<std::string(int)> state_name;
  /// Step-size collapse [s], >= 0: a call of advance() whose steps, counted in windows of `collapse_window` steps,
  /// cover less than this each on average fails at once (flag "CV_TOO_MUCH_WORK", "the step size collapsed"),
  /// naming the time and the limiting state, instead of creeping on until max_num_steps are spent (an absurd gain
  /// once took 40 s of wall time to fail at t = 0.26 ms). 0: no check. No plant of this library legitimately needs
  /// 20,000 steps below 1 ns each (its fastest modes are kHz gear and bristle modes, stepped in µs).
  double collapse_mean_step = 1e-9;
  long collapse_window = 20000;  ///< steps per window of the collapse check (>= 1)
  /// Step of Method::Rosenbrock [s], >= 0. sim::Simulator takes 0 as the plant's sample period (the control period);
  /// a step given with a sampled plant must be that period or an integer fraction of it. The steps lie on the grid
  /// k·fixed_step (k integer); a stop time or a located root between two grid points adds one short step to it.
  double fixed_step = 0.0;
  /// Method::Rosenbrock: right-hand-side Jacobian evaluated (and the matrix I − γhJ factorised) every this many steps,
  /// >= 1, and after every restart that does not reuse it. ROS2 keeps order 2 with an outdated Jacobian (a W-method);
  /// a stale one weakens only the damping of the fastest modes.
  int jacobian_every = 1;
  /// Method::Rosenbrock: with a value θ > 0, a Jacobian is also kept for as long as it describes each step: after
  /// every step the linearisation defect along the first stage, d = f(tₙ + h, yₙ + hk₁) − f(tₙ, yₙ) − W·hk₁ − h·fₜ (the
  /// same held inputs at both points), is compared with the change of f itself in the weighted RMS norm of the
  /// tolerances, and ‖d‖ > θ‖Δf‖ refreshes the Jacobian at the next step (at the latest every jacobian_every steps).
  /// 0 (default): only jacobian_every counts. The experiment files' `jacobian_every: adaptive` is θ = 0.2 (0.02 with
  /// resolve_oscillations) with jacobian_every = kAdaptiveJacobianEvery (1e6 steps: 50 s at 20 kHz) (docs/design.md,
  /// "Jacobian reuse"; setAdaptiveJacobian).
  double jacobian_defect = 0.0;
  /// Method::Rosenbrock: the rows of the plant's oscillatory states (Plant::oscillatoryStates) are taken with
  /// ROS2's other L-stable γ, 1 − 1/√2, instead of 1 + 1/√2 (W's rows scaled by their ratio: still a W-method of order
  /// 2), on every step that is not shortened for a growing mode (nor has a negative determinant with the rows scaled:
  /// SolverStats::damped_steps). A plant that declares no such states is refused. A lightly damped mode at ωh = 1.66 (the UR5 drives'
  /// 5.3 kHz motor–gear mode at 50 µs) then keeps 98 % of its amplitude per step instead of 46 %, which is what
  /// noise-driven statistics of sampled control need (docs/design.md, "Resolving the drive trains' oscillations").
  /// The price: such rows tolerate a Jacobian whose stiff eigenvalues have moved by 17 % (6.8× with 1 + 1/√2), so a
  /// kept Jacobian needs jacobian_defect ≤ kResolveMaxJacobianDefect (`jacobian_every: adaptive` gives
  /// kResolveJacobianDefect: set this before calling setAdaptiveJacobian) and jacobian_every > 1 without a defect test
  /// is refused. A Jacobian per step is safe but less accurate on the UR5 twin than the adaptive one (its stale W damps
  /// the wrists' bristle transient at the stick less; docs/design.md). Default false.
  bool resolve_oscillations = false;
  /// BDF: let the plant's Jacobian use its analytic parts (sim::JacobianKind::Analytic: for the robot with drives the
  /// multibody's columns from the analytic ABA derivatives, fewer right-hand sides). false (default): difference
  /// quotients, as the shipped calibrations were made (BDF's result moves within its tolerance with its Jacobian).
  /// The fixed-step method always uses the analytic parts. Read by sim::Simulator and sim::simulate.
  bool analytic_jacobian = false;
};

/// `jacobian_every: adaptive` (experiment files, Python): CvodeOptions::jacobian_every and jacobian_defect so set.
inline constexpr int kAdaptiveJacobianEvery = 1000000;
inline constexpr double kAdaptiveJacobianDefect = 0.2;
/// The adaptive Jacobian's defect with resolve_oscillations (measured on the UR5 twin: 0.01, 0.02 and 0.05 stay within
/// the validation protocol's accuracy, 0.2 diverged at a wrist's velocity reversal), and the largest accepted.
inline constexpr double kResolveJacobianDefect = 0.02;
inline constexpr double kResolveMaxJacobianDefect = 0.05;
/// Sets `o` to the fixed step's adaptive Jacobian (`jacobian_every: adaptive`), with the defect that suits
/// o.resolve_oscillations.
inline void setAdaptiveJacobian(CvodeOptions& o) {
  o.jacobian_every = kAdaptiveJacobianEvery;
  o.jacobian_defect = o.resolve_oscillations ? kResolveJacobianDefect : kAdaptiveJacobianDefect;
}

/// BDF capped at order 2 with the given tolerances: the default for drive trains. BDF orders 3–5 are not
/// A-stable: lightly damped kHz drive modes (strain-wave gear, stiff springs, LuGre bristles) then force steps
/// of a few µs; BDF2 is A-stable and damps modes it does not resolve (docs/design.md).
CvodeOptions stiffDriveSolver(double rtol, double atol);

/// Solver counters. Counts are cumulative over the integrator's lifetime, including every restart
/// by initialize(); last_order, last_step and current_time refer to the current segment (since the
/// last initialize()).
struct SolverStats {
  long steps = 0;                    ///< internal steps taken
  long rhs_evals = 0;                ///< right-hand side evaluations by the integrator/nonlinear solver
  long rhs_evals_jacobian = 0;       ///< RHS evaluations for difference-quotient Jacobians (BDF only)
  long jac_evals = 0;                ///< Jacobian evaluations, user-supplied or DQ (BDF only)
  long jac_reused = 0;               ///< Jacobian requests answered with the previous one (initialize(…, true))
  long lin_setups = 0;               ///< linear solver setups (Newton matrix factorisations)
  long error_test_failures = 0;      ///< local error test failures
  long nonlinear_iterations = 0;     ///< nonlinear (Newton or fixed-point) iterations
  long nonlinear_conv_failures = 0;  ///< nonlinear solver convergence failures
  int last_order = 0;                ///< method order used on the last internal step (0: no step yet)
  double last_step = 0.0;            ///< size of the last internal step [s] (0: no step yet)
  double current_time = 0.0;         ///< CVODE's internal time t_n [s] (may be ahead of time())
  /// Fixed-step method only: steps shortened (halved, down to 2⁻¹⁵ of the step) because the linearisation had an unstable
  /// real mode the step could not follow (det(I − γhW) < 0; FixedStepIntegrator).
  long split_steps = 0;
  /// Fixed-step method only: full steps retaken from their start with shortened steps because the step after them
  /// found a growing mode they could not see (split_steps counts these too; the discarded step stays counted in
  /// steps; FixedStepIntegrator).
  long retaken_steps = 0;
  /// Fixed-step method with CvodeOptions::resolve_oscillations only: full steps taken with γ = 1 + 1/√2 on every row
  /// because the matrix with the oscillatory rows scaled had a negative determinant (FixedStepIntegrator).
  long damped_steps = 0;
};

/// Right-hand side ydot = f(t, y). `ydot` has size n and must be filled completely; it must not be
/// resized. May throw (preferably jointsim::ComponentError): the integrator stops and raises a
/// SolverError. Called in a hot loop: avoid allocating.
using RhsFunction =
    std::function<void(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> ydot)>;

/// Dense Jacobian J = df/dy (n x n, column-major; J(i, j) = d ydot_i / d y_j) at (t, y), with
/// `ydot` = f(t, y) already evaluated. J is zero on entry, so only non-zeros need to be written (with a
/// JacobianStructure: zero inside the structure; entries outside it are never read, whatever they hold).
/// May throw like RhsFunction.
using JacobianFunction =
    std::function<void(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                       const Eigen::Ref<const Eigen::VectorXd>& ydot, Eigen::Ref<Eigen::MatrixXd> J)>;

/// Jacobian by differences that the caller organises itself (e.g. by structure): as JacobianFunction, plus an
/// increment per state modelled on CVODE's own difference quotients, inc_j = max(√ε |y_j|, m / w_j) with w the
/// error weights and m = 1000 |h| ε n ‖f‖_w (SUNDIALS' cvLsDenseDQJac; h here is CVODE's planned step, which
/// can differ from the step being attempted after a failure or a stop time, so the increments are close to,
/// not always equal to, CVODE's).
using DifferenceJacobianFunction =
    std::function<void(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                       const Eigen::Ref<const Eigen::VectorXd>& ydot, const Eigen::Ref<const Eigen::VectorXd>& inc,
                       Eigen::Ref<Eigen::MatrixXd> J)>;

/// Root (event) functions g(t, y) (size n_roots): CVODE locates sign changes of each component to its
/// tolerance and stops there. Must be pure like the right-hand side.
using RootFunction =
    std::function<void(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> g)>;

/// What sim::Simulator asks of an integrator of y' = f(t, y): CVODE (CvodeIntegrator) or the fixed-step method
/// (FixedStepIntegrator, Method::Rosenbrock). The members mean what CvodeIntegrator's documentation says.
class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual void initialize(double t0, const Eigen::Ref<const Eigen::VectorXd>& y0, bool reuse_jacobian) = 0;
  virtual double advance(double t_out, Eigen::Ref<Eigen::VectorXd> y_out) = 0;
  virtual void setStopTime(double t_stop) = 0;
  virtual void setStepLimit(long steps) = 0;
  virtual void setDifferenceJacobian(DifferenceJacobianFunction jacobian) = 0;
  virtual void setJacobianStructure(JacobianStructure structure) = 0;
  virtual double jumpError(const Eigen::Ref<const Eigen::VectorXd>& f_old,
                           const Eigen::Ref<const Eigen::VectorXd>& f_new, double h_max) const = 0;
  /// True where jumpError() is 0 whatever f_old and f_new are (no history to keep): the caller then need not evaluate
  /// them (two right-hand sides per sample under sampled control).
  virtual bool jumpErrorIsZero() const { return false; }
  virtual void setRootFunction(int n_roots, RootFunction g) = 0;
  virtual bool rootFound() const = 0;
  virtual const std::vector<int>& rootDirections() const = 0;
  virtual double lastStep(Eigen::Ref<Eigen::VectorXd> y) const = 0;
  virtual double time() const = 0;
  virtual SolverStats stats() const = 0;
  virtual long steps() const = 0;
  virtual const CvodeOptions& options() const = 0;
  /// `invariant()` true when f does not depend on t explicitly at the current state (Plant::timeInvariant), asked at
  /// each Jacobian evaluation; an integrator that does not use ∂f/∂t ignores it (CVODE).
  virtual void setTimeInvariance(std::function<bool()> /*invariant*/) {}
  /// The plant's oscillatory states (Plant::oscillatoryStates); an integrator that does not treat them apart ignores
  /// them (CVODE, and the fixed step without CvodeOptions::resolve_oscillations).
  virtual void setOscillatoryStates(std::vector<int> /*states*/) {}
};

/// CVODE integrator for y' = f(t, y), y in R^n.
///
/// Usage: construct, initialize(t0, y0), then advance(t_out, y) repeatedly. After a discontinuity
/// (e.g. an event changing the right-hand side or a state jump) call initialize(t, y) again to
/// restart the multistep history (CVodeReInit); options and solver objects are kept.
///
/// Not copyable; movable (a moved-from integrator may only be destroyed or assigned to). Not
/// thread-safe; distinct instances are independent.
class CvodeIntegrator final : public Integrator {
 public:
  /// \param n         number of states (> 0)
  /// \param rhs       right-hand side (non-empty)
  /// \param options   settings, validated here
  /// \param jacobian  optional analytic Jacobian, used with Method::BDF (ignored for Adams); when
  ///                  empty, BDF uses CVODE's internal difference-quotient Jacobian
  /// \throws InputError on invalid arguments/options
  CvodeIntegrator(int n, RhsFunction rhs, CvodeOptions options = {}, JacobianFunction jacobian = nullptr);
  ~CvodeIntegrator();
  CvodeIntegrator(const CvodeIntegrator&) = delete;
  CvodeIntegrator& operator=(const CvodeIntegrator&) = delete;
  CvodeIntegrator(CvodeIntegrator&&) noexcept;
  CvodeIntegrator& operator=(CvodeIntegrator&&) noexcept;

  /// Set the initial condition y(t0) = y0 [s, state units]. The first call sets up CVODE
  /// (CVodeInit, tolerances, solvers); later calls restart it (CVodeReInit) from (t0, y0), which
  /// may be any time (also backwards). A stop time set with setStopTime() stays in force.
  /// \throws InputError if y0 has the wrong size or t0 / y0 is not finite
  /// \throws SolverError if CVODE rejects the setup
  void initialize(double t0, const Eigen::Ref<const Eigen::VectorXd>& y0);
  /// Restart at an input jump: as initialize(t0, y0), but the first Jacobian CVODE asks for is the last one
  /// evaluated (when there is one; BDF with a plant or user Jacobian or a difference Jacobian of its own). Where
  /// the state is continuous and only held inputs changed, the Jacobian ∂f/∂y a moment before is a good Newton
  /// matrix; it affects the Newton iteration's convergence only, never the accuracy of the step (the residual is
  /// always the right-hand side itself). Should the iteration fail to converge, CVODE asks again and gets a fresh
  /// Jacobian. Saves one Jacobian per restart (51 µs on the UR5 twin) under sampled control.
  void initialize(double t0, const Eigen::Ref<const Eigen::VectorXd>& y0, bool reuse_jacobian) override;

  /// Integrate towards t_out [s] (CV_NORMAL mode: internal steps may overshoot t_out, the result
  /// is interpolated) and store y(t) in y_out (size n). Returns the time reached: t_out, or the stop
  /// time if one is set and lies between time() and t_out.
  /// \throws InputError if y_out has the wrong size or t_out is not finite
  /// \throws jointsim::Error if initialize() was never called
  /// \throws SolverError on any CVODE failure or exception from the RHS/Jacobian. If the cause was
  ///         an exception, the SolverError is thrown with std::throw_with_nested (the original can
  ///         be recovered with std::rethrow_if_nested) and its flag() is "RHS_EXCEPTION". y_out is
  ///         left unchanged on failure.
  double advance(double t_out, Eigen::Ref<Eigen::VectorXd> y_out) override;

  /// Never step past t_stop [s]: advance() returns at t_stop exactly if t_out lies beyond it. The
  /// stop time is one-shot: it is cleared once advance() has returned at it (as in SUNDIALS >= 6.5).
  /// May be set before initialize(). Because CVODE's internal steps overshoot the requested output
  /// time (see SolverStats::current_time), a stop time must be set before the integrator has stepped
  /// past it; initialize() resets the internal time.
  /// \throws InputError if t_stop is not finite or CVODE has already stepped past it.
  void setStopTime(double t_stop) override;
  /// Remove a stop time set with setStopTime().
  void clearStopTime();

  /// Budget of internal steps over the integrator's whole life, restarts included (0: none, the
  /// default). advance() never takes more: the step that would exceed it ends the call with a
  /// SolverError of flag "STEP_BUDGET" (stats().steps is then limit + 1). Unlike max_num_steps, which
  /// bounds one call of advance(), this bounds the run, and is enforced inside the call, so a single
  /// output interval cannot spend more than the budget.
  /// \throws InputError if steps < 0.
  void setStepLimit(long steps) override;

  /// A Jacobian by differences organised by the caller (see DifferenceJacobianFunction) in place of the one given
  /// at construction or CVODE's dense difference quotients; BDF only; call before initialize().
  void setDifferenceJacobian(DifferenceJacobianFunction jacobian) override;
  /// Factorise the Newton matrix by block elimination over `structure` (validated here; BDF with the Eigen
  /// dense solver only; call before initialize()). The Jacobian must respect the structure: entries outside it
  /// (between two blocks, or hub couplings a block did not declare) are ignored, taken as 0. A block (or the hub's
  /// Schur complement) that is numerically singular falls back to the dense LU for that factorisation, of the same
  /// matrix (the structure's entries, 0 elsewhere).
  void setJacobianStructure(JacobianStructure structure) override;

  /// Where an input jumped at time() (the integrator stopped there), the local error the multistep history would
  /// carry into the next step: h ‖f_new − f_old‖_w, the weighted RMS norm (CVODE's error weights) of the jump of the
  /// derivative at (time(), y) from the old inputs (f_old) to the new ones (f_new), times h = min(the next step
  /// size, h_max). About 1 or less: the next step passes the error test with the history kept; far above: the step
  /// would have to shrink by that factor (a restart is cheaper). +∞ before the first step of a segment.
  double jumpError(const Eigen::Ref<const Eigen::VectorXd>& f_old, const Eigen::Ref<const Eigen::VectorXd>& f_new,
                   double h_max) const override;

  /// Installs root functions (call before initialize(); they persist across restarts). advance() then
  /// returns early at a located root: rootFound() is true and rootDirections() gives, per function,
  /// +1 (rising), −1 (falling) or 0 (no crossing).
  void setRootFunction(int n_roots, RootFunction g) override;
  bool rootFound() const override;
  const std::vector<int>& rootDirections() const override;

  /// The state at CVODE's last accepted internal step, where a caller may go on from after a failed or stopped
  /// advance() (e.g. a budget or a stop request raised in the right-hand side): writes y(t_n) into `y` (size n) and
  /// returns t_n [s]. Returns NaN and leaves `y` untouched when no step was taken since the last initialize().
  double lastStep(Eigen::Ref<Eigen::VectorXd> y) const override;

  /// Time of the last result [s]: t0 after initialize(), the value returned by advance(), or after a
  /// failure CVODE's internal time at the failure. NaN before initialize().
  double time() const override;
  /// Number of states n.
  int size() const;
  /// Solver counters, see SolverStats.
  SolverStats stats() const override;
  /// Internal steps so far, over all restarts (stats().steps, without the other counters' cost).
  long steps() const override;
  /// The options given at construction.
  const CvodeOptions& options() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace jointsim::sim
