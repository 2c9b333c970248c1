#include "jointsim/sim/cvode_integrator.hpp"

#include <Eigen/LU>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_types.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <limits>
#include <sstream>
#include <type_traits>
#include <utility>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "sim/block_linear_solver.hpp"
#include "sim/callback_exception.hpp"

static_assert(std::is_same<realtype, double>::value, "SUNDIALS must be built in double precision");

namespace jointsim::sim {

namespace {

// ------------------------------------------------------------------ fast dense matrix operations
// SUNDIALS 6.4's dense copy and A = cA + I loop over column pointers element by element; at every Newton matrix
// setup CVODE calls both on the n × n Jacobian (a third of the UR5 twin's run time under sampled control). The
// same operations on the same SUNDenseMatrix storage, vectorised; clones (CVODE's saved Jacobian) get them too.
int fastDenseCopy(SUNMatrix A, SUNMatrix B) {
  if (SM_ROWS_D(A) != SM_ROWS_D(B) || SM_COLUMNS_D(A) != SM_COLUMNS_D(B)) return SUNMAT_ILL_INPUT;
  std::copy_n(SM_DATA_D(A), SM_LDATA_D(A), SM_DATA_D(B));
  return SUNMAT_SUCCESS;
}
int fastDenseScaleAddI(realtype c, SUNMatrix A) {
  Eigen::Map<Eigen::MatrixXd> m(SM_DATA_D(A), SM_ROWS_D(A), SM_COLUMNS_D(A));
  m *= c;
  m.diagonal().array() += 1.0;
  return SUNMAT_SUCCESS;
}
SUNMatrix fastDenseClone(SUNMatrix A);
void useFastDenseOps(SUNMatrix A) {
  A->ops->copy = fastDenseCopy;
  A->ops->scaleaddi = fastDenseScaleAddI;
  A->ops->clone = fastDenseClone;
}
SUNMatrix fastDenseClone(SUNMatrix A) {
  SUNMatrix B = SUNDenseMatrix(SM_ROWS_D(A), SM_COLUMNS_D(A), A->sunctx);
  if (B != nullptr) useFastDenseOps(B);
  return B;
}

// ------------------------------------------------------------------ structured dense matrix operations
// With a Jacobian structure, the plant writes only the structure's entries (structureRuns) and every other entry of
// the Jacobian, of CVODE's saved copy and of the Newton matrix stays 0: zeroing, copying and A = cA + I then touch
// only those entries (O(n) of a drive chain instead of O(n²): at 24 drives these three were 15 % of a step). The
// content extends SUNDIALS' dense content (first member), so the SM_*_D macros and SUNMatDestroy_Dense still apply.
struct StructuredDenseContent {
  _SUNMatrixContent_Dense dense;
  const std::vector<EntryRun>* runs;  // owned by the integrator, which destroys its matrices first
};
const std::vector<EntryRun>& runsOf(SUNMatrix A) { return *static_cast<StructuredDenseContent*>(A->content)->runs; }
int structuredZero(SUNMatrix A) {
  realtype* d = SM_DATA_D(A);
  const sunindextype ld = SM_ROWS_D(A);
  for (const EntryRun& r : runsOf(A)) std::fill_n(d + r.col * ld + r.row, r.len, 0.0);
  return SUNMAT_SUCCESS;
}
int structuredCopy(SUNMatrix A, SUNMatrix B) {
  if (SM_ROWS_D(A) != SM_ROWS_D(B) || SM_COLUMNS_D(A) != SM_COLUMNS_D(B)) return SUNMAT_ILL_INPUT;
  const realtype* a = SM_DATA_D(A);
  realtype* b = SM_DATA_D(B);
  const sunindextype ld = SM_ROWS_D(A);
  for (const EntryRun& r : runsOf(A)) std::copy_n(a + r.col * ld + r.row, r.len, b + r.col * ld + r.row);
  return SUNMAT_SUCCESS;
}
int structuredScaleAddI(realtype c, SUNMatrix A) {
  realtype* d = SM_DATA_D(A);
  const sunindextype ld = SM_ROWS_D(A);
  for (const EntryRun& r : runsOf(A)) {
    realtype* p = d + r.col * ld + r.row;
    for (int i = 0; i < r.len; ++i) p[i] *= c;
  }
  for (sunindextype i = 0; i < ld; ++i) d[i * ld + i] += 1.0;  // (the diagonal lies in the structure)
  return SUNMAT_SUCCESS;
}
SUNMatrix structuredClone(SUNMatrix A);
/// Makes A (a fresh SUNDenseMatrix) structured: all of it zero, its operations the structured ones.
bool makeStructured(SUNMatrix A, const std::vector<EntryRun>* runs) {
  auto* c = static_cast<StructuredDenseContent*>(std::malloc(sizeof(StructuredDenseContent)));
  if (c == nullptr) return false;
  c->dense = *SM_CONTENT_D(A);
  c->runs = runs;
  std::free(A->content);
  A->content = c;
  std::fill_n(SM_DATA_D(A), SM_LDATA_D(A), 0.0);
  A->ops->zero = structuredZero;
  A->ops->copy = structuredCopy;
  A->ops->scaleaddi = structuredScaleAddI;
  A->ops->clone = structuredClone;
  return true;
}
SUNMatrix structuredClone(SUNMatrix A) {
  SUNMatrix B = SUNDenseMatrix(SM_ROWS_D(A), SM_COLUMNS_D(A), A->sunctx);
  if (B != nullptr && !makeStructured(B, &runsOf(A))) {
    SUNMatDestroy(B);
    return nullptr;
  }
  return B;
}

// ------------------------------------------------------------------ fast weighted RMS norm
// CVODE measures every local error and Newton correction with N_VWrmsNorm; SUNDIALS 6.4's serial version sums
// (x_i w_i)² in a scalar loop (8 % of the UR5 twin's run). The same norm with Eigen's vectorised reduction: the
// sum is taken in another order, so the value differs in the last bits and step sequences change at rounding level
// (every integrator, golden and accuracy test passes unchanged). Clones of the
// state vector (all of CVODE's work vectors) inherit the operation.
realtype fastWrmsNorm(N_Vector x, N_Vector w) {
  const Eigen::Index n = NV_LENGTH_S(x);
  const Eigen::Map<const Eigen::ArrayXd> xa(NV_DATA_S(x), n), wa(NV_DATA_S(w), n);
  return std::sqrt((xa * wa).square().sum() / static_cast<double>(n));
}
void useFastVectorOps(N_Vector v) { v->ops->nvwrmsnorm = fastWrmsNorm; }

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Name of a CVODE return flag. CVodeGetReturnFlagName returns a malloc'ed string the caller frees.
std::string flagName(int flag) {
  char* raw = CVodeGetReturnFlagName(flag);
  if (raw == nullptr) return "CV_FLAG_" + std::to_string(flag);
  std::string name(raw);
  std::free(raw);
  return name;
}

std::string formatTime(double t) {
  std::ostringstream os;
  os.precision(10);
  os << t;
  return os.str();
}

}  // namespace

struct CvodeIntegrator::Impl {
  int n = 0;
  RhsFunction rhs;
  JacobianFunction jac;
  DifferenceJacobianFunction diff_jac;
  JacobianStructure structure;
  std::vector<EntryRun> runs;     // structureRuns(structure): the entries the matrices' structured operations touch
  N_Vector ewt = nullptr;         // error weights (diff_jac's increments, jumpError)
  Eigen::VectorXd increments;     // diff_jac's increments
  Eigen::MatrixXd last_jacobian;  // the last Jacobian evaluated (initialize(…, true)); empty: none yet
  bool reuse_jacobian = false;    // answer the next Jacobian request with last_jacobian
  long jac_reused = 0;            // requests so answered (all segments)
  CvodeOptions opts;

  SUNContext ctx = nullptr;
  void* mem = nullptr;
  N_Vector y = nullptr;              // state work/output vector (also the template vector)
  SUNMatrix A = nullptr;             // BDF only
  SUNLinearSolver LS = nullptr;      // BDF only
  SUNNonlinearSolver NLS = nullptr;  // Adams only (BDF uses CVODE's own default Newton solver)

  bool initialized = false;
  bool fresh = true;     // no CVode call since the last (Re)Init
  double t0 = kNaN;      // time of the last initialize()
  double t_last = kNaN;  // last result time (see time())

  bool stop_set = false;  // user stop time requested
  double stop_time = 0.0;
  bool cvode_tstop_touched = false;  // CVodeSetStopTime was ever called (must be neutralised on clear)

  SolverStats base;     // counters accumulated from earlier segments
  long step_limit = 0;  // setStepLimit(): steps over all segments (0: none)
  long mxstep_set = 0;  // the value last given to CVodeSetMaxNumSteps
  int n_roots = 0;
  RootFunction root_fn;
  bool root_found = false;
  std::vector<int> root_dirs;

  // Failure capture (filled from inside the C callbacks; no allocation on the success path).
  std::exception_ptr callback_exception;
  double callback_exception_time = kNaN;
  const char* callback_exception_source = "";  // "right-hand side" or "Jacobian"
  bool poisoned = false;                       // a callback failed fatally in this call: fail all further calls
  bool nonfinite_seen = false;
  long nonfinite_count = 0;  // non-finite RHS/Jacobian results in this advance() call
  double nonfinite_time = kNaN;
  Eigen::Index nonfinite_row = -1;
  Eigen::Index nonfinite_col = -1;  // -1 for the RHS
  double nonfinite_value = 0.0;
  std::string cvode_message;        // last CVODE error text (from the error handler)
  std::string cvode_first_warning;  // first CVODE warning text in this call
  std::string cvode_warning;        // last CVODE warning text in this call
  long cvode_warnings = 0;

  ~Impl() {
    if (mem != nullptr) CVodeFree(&mem);
    if (NLS != nullptr) SUNNonlinSolFree(NLS);
    if (LS != nullptr) SUNLinSolFree(LS);
    if (A != nullptr) SUNMatDestroy(A);
    if (y != nullptr) N_VDestroy(y);
    if (ewt != nullptr) N_VDestroy(ewt);
    if (ctx != nullptr) SUNContext_Free(&ctx);
  }

  std::string prefix() const {
    std::string p = "CVODE integrator";
    if (!opts.component.empty()) p += " (" + opts.component + ")";
    return p;
  }

  void resetCapture() {
    callback_exception = nullptr;
    callback_exception_time = kNaN;
    poisoned = false;
    nonfinite_seen = false;
    nonfinite_count = 0;
    cvode_message.clear();
    cvode_first_warning.clear();
    cvode_warning.clear();
    cvode_warnings = 0;
  }

  double cvodeTime() const {
    double t = kNaN;
    if (mem != nullptr && CVodeGetCurrentTime(mem, &t) != CV_SUCCESS) t = kNaN;
    return t;
  }

  /// "; limiting state: NAME (the largest weighted local error |e_i|·w_i of the last step)", or "" when CVODE cannot
  /// say (no step taken yet).
  std::string limitingState() const {
    if (mem == nullptr || y == nullptr) return {};
    N_Vector ele = N_VClone(y), ewt = N_VClone(y);
    std::string out;
    if (ele != nullptr && ewt != nullptr && CVodeGetEstLocalErrors(mem, ele) == CV_SUCCESS &&
        CVodeGetErrWeights(mem, ewt) == CV_SUCCESS) {
      const sunrealtype* e = N_VGetArrayPointer(ele);
      const sunrealtype* w = N_VGetArrayPointer(ewt);
      const sunindextype n = N_VGetLength(y);
      sunindextype worst = -1;
      double largest = 0.0;
      for (sunindextype i = 0; i < n; ++i) {
        const double v = std::abs(e[i] * w[i]);
        if (std::isfinite(v) && v > largest) {
          largest = v;
          worst = i;
        }
      }
      if (worst >= 0) {
        std::string name = opts.state_name ? opts.state_name(static_cast<int>(worst)) : std::string();
        if (name.empty()) name = "y[" + std::to_string(worst) + "]";
        out = "; limiting state: " + name + " (largest weighted local error of the last step, " +
              formatNumber(largest, 3) + ")";
      }
    }
    if (ele != nullptr) N_VDestroy(ele);
    if (ewt != nullptr) N_VDestroy(ewt);
    return out;
  }

  /// Throw a SolverError for a failed CVODE call `what` that returned `flag`.
  [[noreturn]] void fail(const char* what, int flag, double t) {
    const std::string name = flagName(flag);
    std::string component = opts.component;
    std::ostringstream msg;
    if (callback_exception) {
      t = callback_exception_time;
      const std::string original = callbackExceptionText(callback_exception, component);
      msg << "CVODE integrator";
      if (!component.empty()) msg << " (" << component << ")";
      msg << ": " << callback_exception_source << " threw at t = " << formatTime(t) << " s: " << original << " ["
          << what << " returned " << name << ", flag RHS_EXCEPTION]";
      if (!cvode_message.empty()) msg << "; CVODE: " << cvode_message;
      auto ep = callback_exception;
      callback_exception = nullptr;
      try {
        std::rethrow_exception(ep);
      } catch (...) {
        std::throw_with_nested(SolverError(msg.str(), t, "RHS_EXCEPTION", component));
      }
    }
    msg << prefix() << ": " << what << " failed with " << name << " at t = " << formatTime(t) << " s";
    if (!cvode_message.empty()) msg << ": " << cvode_message;
    if (nonfinite_seen) {
      msg << "; the " << (nonfinite_col < 0 ? "right-hand side" : "Jacobian") << " returned a non-finite value (";
      if (nonfinite_col < 0) {
        msg << "ydot[" << nonfinite_row << "]";
      } else {
        msg << "J(" << nonfinite_row << ", " << nonfinite_col << ")";
      }
      msg << " = " << nonfinite_value << ") at t = " << formatTime(nonfinite_time) << " s, " << nonfinite_count
          << " time(s) in this call";
      if (nonfinite_count > opts.max_nonfinite_retries) msg << " (retry limit max_nonfinite_retries exceeded)";
    } else {
      msg << limitingState();
    }
    if (cvode_warnings > 0) {
      msg << "; CVODE warning";
      if (cvode_warnings > 1) msg << "s (" << cvode_warnings << "), first: " << cvode_first_warning << "; last";
      msg << ": " << cvode_warning;
    }
    throw SolverError(msg.str(), t, name, component);
  }

  /// Check the return flag of a setup call.
  void check(int flag, const char* what) {
    if (flag < 0) fail(what, flag, initialized ? cvodeTime() : t0);
  }

  // ------------------------------------------------------------------ C callbacks
  /// Record a non-finite RHS/Jacobian result at t: recoverable (CVODE retries with a smaller step)
  /// until the per-call budget is spent, then unrecoverable. The budget stops CVODE from creeping
  /// towards a time beyond which the RHS is always non-finite until max_num_steps is exhausted.
  int nonfiniteResult(double t) noexcept {
    nonfinite_seen = true;
    nonfinite_time = t;
    if (++nonfinite_count > opts.max_nonfinite_retries) {
      poisoned = true;
      return -1;
    }
    return 1;
  }

  static int rhsCallback(realtype t, N_Vector yv, N_Vector ydotv, void* user_data) noexcept {
    auto* self = static_cast<Impl*>(user_data);
    // Once a callback has thrown, fail every further call without running user code. Besides not
    // re-entering a component in an unknown state, this is needed because the SUNDIALS 6.4
    // fixed-point solver (Adams) treats a failing RHS as a recoverable convergence failure and would
    // otherwise keep retrying with smaller steps until max_num_steps.
    if (self->poisoned) return -1;
    const Eigen::Map<const Eigen::VectorXd> ym(N_VGetArrayPointer(yv), self->n);
    Eigen::Map<Eigen::VectorXd> ydm(N_VGetArrayPointer(ydotv), self->n);
    try {
      self->rhs(t, ym, ydm);
    } catch (...) {
      self->callback_exception = std::current_exception();
      self->callback_exception_time = t;
      self->callback_exception_source = "right-hand side";
      self->poisoned = true;
      return -1;  // unrecoverable
    }
    if (self->opts.check_finite && !ydm.allFinite()) {
      for (Eigen::Index i = 0; i < self->n; ++i) {
        if (!std::isfinite(ydm[i])) {
          self->nonfinite_row = i;
          self->nonfinite_value = ydm[i];
          break;
        }
      }
      self->nonfinite_col = -1;
      return self->nonfiniteResult(t);
    }
    return 0;
  }

  static int rootCallback(realtype t, N_Vector yv, realtype* gout, void* user_data) noexcept {
    auto* self = static_cast<Impl*>(user_data);
    const Eigen::Map<const Eigen::VectorXd> ym(N_VGetArrayPointer(yv), self->n);
    Eigen::Map<Eigen::VectorXd> gm(gout, self->n_roots);
    try {
      self->root_fn(t, ym, gm);
    } catch (...) {
      self->callback_exception = std::current_exception();
      self->callback_exception_time = t;
      self->callback_exception_source = "root function";
      return -1;
    }
    return 0;
  }

  static int jacCallback(realtype t, N_Vector yv, N_Vector fyv, SUNMatrix J, void* user_data, N_Vector, N_Vector,
                         N_Vector) noexcept {
    auto* self = static_cast<Impl*>(user_data);
    if (self->poisoned) return -1;
    const Eigen::Map<const Eigen::VectorXd> ym(N_VGetArrayPointer(yv), self->n);
    const Eigen::Map<const Eigen::VectorXd> fm(N_VGetArrayPointer(fyv), self->n);
    // SUNDenseMatrix storage is column-major with leading dimension M = n.
    Eigen::Map<Eigen::MatrixXd> jm(SM_DATA_D(J), self->n, self->n);
    if (self->reuse_jacobian) {
      self->reuse_jacobian = false;
      if (self->last_jacobian.size() > 0) {
        jm = self->last_jacobian;
        ++self->jac_reused;
        return 0;
      }
    }
    try {
      if (self->diff_jac) {
        // The increments of SUNDIALS' cvLsDenseDQJac (srur = √uround, MIN_INC_MULT = 1000).
        double h = 0.0;
        CVodeGetCurrentStep(self->mem, &h);
        CVodeGetErrWeights(self->mem, self->ewt);
        const Eigen::Map<const Eigen::VectorXd> w(N_VGetArrayPointer(self->ewt), self->n);
        const double uround = std::numeric_limits<double>::epsilon();
        const double fnorm = std::sqrt((fm.array() * w.array()).square().sum() / self->n);
        const double min_inc = fnorm != 0.0 ? 1000.0 * std::abs(h) * uround * self->n * fnorm : 1.0;
        for (Eigen::Index j = 0; j < self->n; ++j)
          self->increments[j] = std::max(std::sqrt(uround) * std::abs(ym[j]), min_inc / w[j]);
        SUNMatZero(J);  // (the structure's entries only, with a structure)
        self->diff_jac(t, ym, fm, self->increments, jm);
      } else {
        self->jac(t, ym, fm, jm);
      }
    } catch (...) {
      self->callback_exception = std::current_exception();
      self->callback_exception_time = t;
      self->callback_exception_source = "Jacobian";
      self->poisoned = true;
      return -1;
    }
    if (self->opts.check_finite && !self->jacobianFinite(jm)) {
      bool found = false;
      for (Eigen::Index j = 0; j < self->n && !found; ++j) {
        for (Eigen::Index i = 0; i < self->n && !found; ++i) {
          if (!std::isfinite(jm(i, j))) {
            self->nonfinite_row = i;
            self->nonfinite_col = j;
            self->nonfinite_value = jm(i, j);
            found = true;
          }
        }
      }
      return self->nonfiniteResult(t);
    }
    if (self->runs.empty() || self->last_jacobian.size() == 0) {
      self->last_jacobian = jm;  // sized at the first evaluation only
    } else {
      for (const EntryRun& r : self->runs)
        self->last_jacobian.col(r.col).segment(r.row, r.len) = jm.col(r.col).segment(r.row, r.len);
    }
    return 0;
  }

  /// Whether every entry of the Jacobian is finite (with a structure: its entries; the others are 0).
  bool jacobianFinite(const Eigen::Map<Eigen::MatrixXd>& jm) const {
    if (runs.empty()) return jm.allFinite();
    for (const EntryRun& r : runs)
      if (!jm.col(r.col).segment(r.row, r.len).allFinite()) return false;
    return true;
  }

  static void errCallback(int error_code, const char* module, const char* function, char* msg, void* eh_data) noexcept {
    auto* self = static_cast<Impl*>(eh_data);
    try {
      std::string text =
          std::string("[") + (module ? module : "") + " " + (function ? function : "") + "] " + (msg ? msg : "");
      if (error_code == CV_WARNING) {
        if (self->cvode_warnings == 0) self->cvode_first_warning = text;
        self->cvode_warning = std::move(text);
        ++self->cvode_warnings;
      } else {
        self->cvode_message = std::move(text);
      }
    } catch (...) {
      // Out of memory while recording a diagnostic: drop the text, the flag is still reported.
    }
  }

  // ------------------------------------------------------------------ setup
  void firstInit(double t, N_Vector y0) {
    check(CVodeInit(mem, &Impl::rhsCallback, t, y0), "CVodeInit");
    if (n_roots > 0) check(CVodeRootInit(mem, n_roots, &Impl::rootCallback), "CVodeRootInit");
    if (opts.atol_vector.size() > 0) {
      N_Vector abstol = N_VNew_Serial(n, ctx);
      if (abstol == nullptr) throw Error(prefix() + ": allocation of the tolerance vector failed");
      Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(abstol), n) = opts.atol_vector;
      const int flag = CVodeSVtolerances(mem, opts.rtol, abstol);  // CVODE keeps its own copy
      N_VDestroy(abstol);
      check(flag, "CVodeSVtolerances");
    } else {
      check(CVodeSStolerances(mem, opts.rtol, opts.atol), "CVodeSStolerances");
    }
    if (opts.method == Method::BDF) {
      A = SUNDenseMatrix(n, n, ctx);
      if (A == nullptr) throw Error(prefix() + ": allocation of the dense Jacobian matrix failed");
      runs = jac || diff_jac ? structureRuns(structure, n) : std::vector<EntryRun>{};
      if (runs.empty())
        useFastDenseOps(A);
      else if (!makeStructured(A, &runs))
        throw Error(prefix() + ": allocation of the dense Jacobian matrix failed");
      LS = opts.dense_solver == CvodeOptions::DenseSolver::Eigen ? makeEigenDenseSolver(n, ctx, structure)
                                                                 : SUNLinSol_Dense(y, A, ctx);
      if (LS == nullptr) throw Error(prefix() + ": creation of the dense linear solver failed");
      check(CVodeSetLinearSolver(mem, LS, A), "CVodeSetLinearSolver");
      if (diff_jac && ewt == nullptr) {
        ewt = N_VNew_Serial(n, ctx);
        if (ewt == nullptr) throw Error(prefix() + ": allocation of the error-weight vector failed");
        increments.resize(n);
      }
      if (jac || diff_jac) check(CVodeSetJacFn(mem, &Impl::jacCallback), "CVodeSetJacFn");
      if (opts.stability_limit_detection) check(CVodeSetStabLimDet(mem, SUNTRUE), "CVodeSetStabLimDet");
    } else {
      NLS = SUNNonlinSol_FixedPoint(y, 0, ctx);
      if (NLS == nullptr) throw Error(prefix() + ": creation of the fixed-point nonlinear solver failed");
      check(CVodeSetNonlinearSolver(mem, NLS), "CVodeSetNonlinearSolver");
    }
    check(CVodeSetMaxNumSteps(mem, opts.max_num_steps), "CVodeSetMaxNumSteps");
    mxstep_set = opts.max_num_steps;
    if (opts.max_step > 0.0) check(CVodeSetMaxStep(mem, opts.max_step), "CVodeSetMaxStep");
    if (opts.min_step > 0.0) check(CVodeSetMinStep(mem, opts.min_step), "CVodeSetMinStep");
    if (opts.initial_step != 0.0) check(CVodeSetInitStep(mem, opts.initial_step), "CVodeSetInitStep");
    if (opts.max_order > 0) check(CVodeSetMaxOrd(mem, opts.max_order), "CVodeSetMaxOrd");
    if (opts.method == Method::BDF)
      check(CVodeSetDeltaGammaMaxLSetup(mem, opts.max_gamma_change), "CVodeSetDeltaGammaMaxLSetup");
  }

  /// Add the counters of the current segment to `base` (before a CVodeReInit resets them).
  void accumulate() { addCounters(base, segmentStats()); }

  /// Internal steps over all segments (the one counter the step limit needs; segmentStats() reads them all).
  long stepsSoFar() const {
    long nst = 0;
    if (initialized && !fresh) CVodeGetNumSteps(mem, &nst);
    return base.steps + nst;
  }

  /// Adds the event counters of `from` to `into` (order, step and time are not counters).
  static void addCounters(SolverStats& into, const SolverStats& from) {
    into.steps += from.steps;
    into.rhs_evals += from.rhs_evals;
    into.rhs_evals_jacobian += from.rhs_evals_jacobian;
    into.jac_evals += from.jac_evals;
    into.lin_setups += from.lin_setups;
    into.error_test_failures += from.error_test_failures;
    into.nonlinear_iterations += from.nonlinear_iterations;
    into.nonlinear_conv_failures += from.nonlinear_conv_failures;
  }

  /// Counters of the current segment (zero if CVode was not called since the last (Re)Init: the
  /// linear solver counters are only reset at the first CVode call after a CVodeReInit).
  SolverStats segmentStats() const {
    SolverStats s;
    s.current_time = initialized ? t0 : kNaN;
    if (!initialized || fresh) return s;
    long nsteps = 0, nfe = 0, nsetups = 0, netf = 0;
    int qlast = 0, qcur = 0;
    double hinused = 0, hlast = 0, hcur = 0, tcur = 0;
    if (CVodeGetIntegratorStats(mem, &nsteps, &nfe, &nsetups, &netf, &qlast, &qcur, &hinused, &hlast, &hcur, &tcur) ==
        CV_SUCCESS) {
      s.steps = nsteps;
      s.rhs_evals = nfe;
      s.lin_setups = nsetups;
      s.error_test_failures = netf;
      s.last_order = qlast;
      s.last_step = hlast;
      s.current_time = tcur;
    }
    long v = 0;
    if (CVodeGetNumNonlinSolvIters(mem, &v) == CV_SUCCESS) s.nonlinear_iterations = v;
    if (CVodeGetNumNonlinSolvConvFails(mem, &v) == CV_SUCCESS) s.nonlinear_conv_failures = v;
    if (opts.method == Method::BDF) {
      if (CVodeGetNumJacEvals(mem, &v) == CV_SUCCESS) s.jac_evals = v;
      if (CVodeGetNumLinRhsEvals(mem, &v) == CV_SUCCESS) s.rhs_evals_jacobian = v;
    }
    return s;
  }
};

// ==================================================================== public API

CvodeIntegrator::CvodeIntegrator(int n, RhsFunction rhs, CvodeOptions options, JacobianFunction jacobian)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const std::string who =
      "CvodeIntegrator" + (options.component.empty() ? std::string() : " (" + options.component + ")");
  auto bad = [&who](const std::string& what) { throw InputError(who + ": " + what); };

  if (n <= 0) bad("number of states must be positive, got " + std::to_string(n));
  if (!rhs) bad("right-hand side function is empty");
  if (!(options.rtol > 0.0) || !std::isfinite(options.rtol)) {
    bad("rtol must be a finite number > 0, got " + formatTime(options.rtol));
  }
  if (options.atol_vector.size() > 0) {
    if (options.atol_vector.size() != n) {
      bad("atol_vector has " + std::to_string(options.atol_vector.size()) + " entries, expected " + std::to_string(n) +
          " (one per state)");
    }
    for (Eigen::Index i = 0; i < n; ++i) {
      const double a = options.atol_vector[i];
      if (!(a >= 0.0) || !std::isfinite(a)) {
        bad("atol_vector[" + std::to_string(i) + "] must be a finite number >= 0, got " + formatTime(a));
      }
    }
  } else if (!(options.atol >= 0.0) || !std::isfinite(options.atol)) {
    bad("atol must be a finite number >= 0, got " + formatTime(options.atol));
  }
  if (!(options.max_step >= 0.0) || !std::isfinite(options.max_step)) {
    bad("max_step must be a finite number >= 0 (0 = unlimited), got " + formatTime(options.max_step));
  }
  if (!(options.min_step >= 0.0) || !std::isfinite(options.min_step)) {
    bad("min_step must be a finite number >= 0, got " + formatTime(options.min_step));
  }
  if (options.max_step > 0.0 && options.min_step > options.max_step) {
    bad("min_step (" + formatTime(options.min_step) + ") exceeds max_step (" + formatTime(options.max_step) + ")");
  }
  if (!std::isfinite(options.initial_step)) bad("initial_step must be finite");
  if (options.max_nonfinite_retries < 0) {
    bad("max_nonfinite_retries must be >= 0, got " + std::to_string(options.max_nonfinite_retries));
  }
  if (!(options.collapse_mean_step >= 0.0) || !std::isfinite(options.collapse_mean_step))
    bad("collapse_mean_step must be a time >= 0 s (0: no check), got " + formatNumber(options.collapse_mean_step));
  if (options.collapse_window < 1)
    bad("collapse_window must be >= 1 step, got " + std::to_string(options.collapse_window));
  if (options.max_num_steps <= 0) {
    bad("max_num_steps must be > 0, got " + std::to_string(options.max_num_steps));
  }
  if (options.method != Method::BDF && options.method != Method::Adams)
    bad("CVODE integrates with Method::BDF or Method::Adams (Method::Rosenbrock is sim::FixedStepIntegrator's)");
  const int order_limit = options.method == Method::BDF ? 5 : 12;
  if (options.max_order < 0 || options.max_order > order_limit) {
    bad("max_order must be 0 (default) or 1.." + std::to_string(order_limit) + " for " +
        (options.method == Method::BDF ? "BDF" : "Adams") + ", got " + std::to_string(options.max_order));
  }
  if (!(options.max_gamma_change > 0.0) || !std::isfinite(options.max_gamma_change)) {
    bad("max_gamma_change must be finite and > 0, got " + formatTime(options.max_gamma_change));
  }
  if (options.stability_limit_detection && options.method != Method::BDF) {
    bad("stability_limit_detection is only available with Method::BDF");
  }

  m.n = n;
  m.rhs = std::move(rhs);
  if (options.method == Method::BDF) m.jac = std::move(jacobian);
  m.opts = std::move(options);

  if (SUNContext_Create(nullptr, &m.ctx) != 0 || m.ctx == nullptr) {
    throw Error(m.prefix() + ": SUNContext_Create failed");
  }
  m.y = N_VNew_Serial(n, m.ctx);
  if (m.y == nullptr) throw Error(m.prefix() + ": allocation of the state vector failed");
  useFastVectorOps(m.y);
  m.mem = CVodeCreate(m.opts.method == Method::BDF ? CV_BDF : CV_ADAMS, m.ctx);
  if (m.mem == nullptr) throw Error(m.prefix() + ": CVodeCreate failed");
  m.check(CVodeSetErrHandlerFn(m.mem, &Impl::errCallback, &m), "CVodeSetErrHandlerFn");
  m.check(CVodeSetUserData(m.mem, &m), "CVodeSetUserData");
}

CvodeIntegrator::~CvodeIntegrator() = default;
CvodeIntegrator::CvodeIntegrator(CvodeIntegrator&&) noexcept = default;
CvodeIntegrator& CvodeIntegrator::operator=(CvodeIntegrator&&) noexcept = default;

void CvodeIntegrator::initialize(double t0, const Eigen::Ref<const Eigen::VectorXd>& y0) { initialize(t0, y0, false); }

void CvodeIntegrator::initialize(double t0, const Eigen::Ref<const Eigen::VectorXd>& y0, bool reuse_jacobian) {
  Impl& m = *impl_;
  if (y0.size() != m.n) {
    throw InputError(m.prefix() + ": initial state has " + std::to_string(y0.size()) + " entries, expected " +
                     std::to_string(m.n));
  }
  if (!std::isfinite(t0)) throw InputError(m.prefix() + ": initial time must be finite");
  if (!y0.allFinite()) throw InputError(m.prefix() + ": initial state contains NaN or Inf");

  m.resetCapture();
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(m.y), m.n) = y0;
  m.t0 = t0;
  if (!m.initialized) {
    m.firstInit(t0, m.y);
    m.initialized = true;
  } else {
    if (!m.fresh) m.accumulate();
    m.check(CVodeReInit(m.mem, t0, m.y), "CVodeReInit");
  }
  m.fresh = true;
  m.t_last = t0;
  m.reuse_jacobian = reuse_jacobian && (m.jac || m.diff_jac);
}

double CvodeIntegrator::advance(double t_out, Eigen::Ref<Eigen::VectorXd> y_out) {
  Impl& m = *impl_;
  if (!m.initialized) throw Error(m.prefix() + ": advance() called before initialize()");
  if (y_out.size() != m.n) {
    throw InputError(m.prefix() + ": output vector has " + std::to_string(y_out.size()) + " entries, expected " +
                     std::to_string(m.n));
  }
  if (!std::isfinite(t_out)) throw InputError(m.prefix() + ": output time must be finite");

  Eigen::Map<const Eigen::VectorXd> ym(N_VGetArrayPointer(m.y), m.n);
  // CVODE rejects a first output time within rounding of t0 (CV_TOO_CLOSE: |tout − t0| <= 2 u max(|t0|, |tout|)), as
  // when a time event and an output time computed differently meet (0.2 + 0.5·69/100 against 545/1000): the state
  // at t0 is the state at t_out to rounding.
  if (m.fresh && std::abs(t_out - m.t0) <= 8.0 * std::numeric_limits<double>::epsilon() *
                                               std::max({std::abs(m.t0), std::abs(t_out), 1e-300})) {
    y_out = ym;
    return t_out;
  }

  m.resetCapture();
  if (m.stop_set) {
    m.check(CVodeSetStopTime(m.mem, m.stop_time), "CVodeSetStopTime");
    m.cvode_tstop_touched = true;
  } else if (m.cvode_tstop_touched) {
    // SUNDIALS 6.4 has no CVodeClearStopTime: push the stop time out of reach in the direction of travel.
    const double far = t_out >= m.t_last ? std::numeric_limits<double>::max() : -std::numeric_limits<double>::max();
    m.check(CVodeSetStopTime(m.mem, far), "CVodeSetStopTime");
  }

  // The run's step budget: this call may take at most the steps left plus one (the one that exceeds it).
  const long call_start_steps = m.stepsSoFar();
  const long budget = m.step_limit > 0
                          ? std::min(m.opts.max_num_steps, std::max(1L, m.step_limit - call_start_steps + 1))
                          : m.opts.max_num_steps;
  // CVODE is called in windows of collapse_window steps so that a collapsed step size is seen after one window
  // (CvodeOptions::collapse_mean_step), not after the whole budget; together they take at most `budget` steps.
  const bool watch = m.opts.collapse_mean_step > 0.0 && m.opts.collapse_window > 0;
  double t_ret = m.t_last;
  int flag = CV_SUCCESS;
  for (;;) {
    const long used = m.stepsSoFar() - call_start_steps;
    const long mxstep = watch ? std::min(budget - used, m.opts.collapse_window) : budget;
    if (mxstep != m.mxstep_set) {
      m.check(CVodeSetMaxNumSteps(m.mem, mxstep), "CVodeSetMaxNumSteps");
      m.mxstep_set = mxstep;
    }
    const double window_t0 = m.cvodeTime();
    const long window_steps0 = m.stepsSoFar();
    flag = CVode(m.mem, t_out, m.y, &t_ret, CV_NORMAL);
    m.fresh = false;
    if (flag != CV_TOO_MUCH_WORK || m.callback_exception || !watch) break;
    const long taken = m.stepsSoFar() - window_steps0;
    const double covered = std::abs(m.cvodeTime() - window_t0);
    if (taken >= m.opts.collapse_window && !(covered >= static_cast<double>(taken) * m.opts.collapse_mean_step)) {
      m.t_last = m.cvodeTime();
      double h = 0.0;
      CVodeGetLastStep(m.mem, &h);
      throw SolverError(m.prefix() + ": the step size collapsed at t = " + formatTime(m.t_last) +
                            " s: " + std::to_string(taken) + " steps covered " + formatNumber(covered, 3) +
                            " s (less than " + formatNumber(m.opts.collapse_mean_step) + " s each; last step " +
                            formatNumber(std::abs(h), 3) + " s)" + m.limitingState() +
                            ". A parameter far beyond reason (a gain, a stiffness) or a discontinuity the solver "
                            "keeps meeting; check the limiting state's component",
                        m.t_last, "CV_TOO_MUCH_WORK", m.opts.component);
    }
    if (m.stepsSoFar() - call_start_steps >= budget) break;  // the call's budget is spent: as one CVode call
  }
  if (flag == CV_TOO_MUCH_WORK && m.step_limit > 0 && !m.callback_exception && m.stepsSoFar() > m.step_limit) {
    m.t_last = m.cvodeTime();
    throw SolverError(m.prefix() + ": more than " + std::to_string(m.step_limit) +
                          " internal steps at t = " + formatTime(m.t_last) + " s (step limit)",
                      m.t_last, "STEP_BUDGET", m.opts.component);
  }
  m.root_found = flag == CV_ROOT_RETURN;
  if (m.root_found) m.check(CVodeGetRootInfo(m.mem, m.root_dirs.data()), "CVodeGetRootInfo");
  if (flag < 0 || m.callback_exception) {
    m.t_last = m.cvodeTime();
    m.fail("CVode", flag, m.t_last);
  }
  // One-shot: cleared once reached, also when CVODE reports the arrival as a normal return (t_out equal
  // to the stop time); otherwise the next advance() would re-arm a stop time already behind us.
  if (flag == CV_TSTOP_RETURN || (m.stop_set && t_ret == m.stop_time)) m.stop_set = false;
  m.t_last = t_ret;
  y_out = ym;
  return t_ret;
}

void CvodeIntegrator::setStopTime(double t_stop) {
  Impl& m = *impl_;
  if (!std::isfinite(t_stop)) throw InputError(m.prefix() + ": stop time must be finite");
  if (m.initialized) {
    // Validate now (CVODE rejects a stop time behind its internal time) so the error surfaces here.
    m.cvode_message.clear();
    const int flag = CVodeSetStopTime(m.mem, t_stop);
    m.cvode_tstop_touched = true;
    if (flag < 0) {
      throw InputError(m.prefix() + ": stop time " + formatTime(t_stop) + " s rejected (" + flagName(flag) +
                       "): " + m.cvode_message + " CVODE's internal time is " + formatTime(m.cvodeTime()) +
                       " s; internal steps overshoot the requested output time, so set the stop time before "
                       "advancing past it (or restart with initialize())");
    }
  }
  m.stop_set = true;
  m.stop_time = t_stop;
}

void CvodeIntegrator::clearStopTime() { impl_->stop_set = false; }

void CvodeIntegrator::setStepLimit(long steps) {
  if (steps < 0) throw InputError(impl_->prefix() + ": step limit must be >= 0 (0: none)");
  impl_->step_limit = steps;
}

double CvodeIntegrator::lastStep(Eigen::Ref<Eigen::VectorXd> y) const {
  const Impl& m = *impl_;
  if (y.size() != m.n) {
    throw InputError(m.prefix() + ": lastStep: output vector has " + std::to_string(y.size()) + " entries, expected " +
                     std::to_string(m.n));
  }
  long steps = 0;
  if (!m.initialized || m.fresh || CVodeGetNumSteps(m.mem, &steps) != CV_SUCCESS || steps == 0) return kNaN;
  const double tn = m.cvodeTime();
  N_Vector out = N_VNew_Serial(m.n, m.ctx);
  if (out == nullptr) return kNaN;
  const int flag = CVodeGetDky(m.mem, tn, 0, out);
  if (flag == CV_SUCCESS) y = Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(out), m.n);
  N_VDestroy(out);
  return flag == CV_SUCCESS ? tn : kNaN;
}

double CvodeIntegrator::time() const { return impl_->t_last; }

int CvodeIntegrator::size() const { return impl_->n; }

long CvodeIntegrator::steps() const { return impl_->stepsSoFar(); }

SolverStats CvodeIntegrator::stats() const {
  const SolverStats cur = impl_->segmentStats();
  SolverStats s = impl_->base;
  Impl::addCounters(s, cur);
  s.last_order = cur.last_order;
  s.last_step = cur.last_step;
  s.current_time = cur.current_time;
  s.jac_reused = impl_->jac_reused;
  s.jac_evals -= impl_->jac_reused;  // CVODE counts every request
  return s;
}

const CvodeOptions& CvodeIntegrator::options() const { return impl_->opts; }

void CvodeIntegrator::setRootFunction(int n_roots, RootFunction g) {
  Impl& m = *impl_;
  if (m.initialized) throw InputError(m.prefix() + ": setRootFunction() must be called before initialize()");
  if (n_roots < 0 || (n_roots > 0 && !g)) throw InputError(m.prefix() + ": invalid root function");
  m.n_roots = n_roots;
  m.root_fn = std::move(g);
  m.root_dirs.assign(static_cast<size_t>(n_roots), 0);
}

double CvodeIntegrator::jumpError(const Eigen::Ref<const Eigen::VectorXd>& f_old,
                                  const Eigen::Ref<const Eigen::VectorXd>& f_new, double h_max) const {
  Impl& m = *impl_;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!m.initialized || m.fresh || f_new.size() != m.n || f_old.size() != m.n) return kInf;
  double h = 0.0;
  if (CVodeGetCurrentStep(m.mem, &h) != CV_SUCCESS) return kInf;
  h = std::min(std::abs(h), std::abs(h_max));
  if (m.ewt == nullptr) {
    m.ewt = N_VNew_Serial(m.n, m.ctx);
    if (m.ewt == nullptr) return kInf;
  }
  if (CVodeGetErrWeights(m.mem, m.ewt) != CV_SUCCESS) return kInf;
  const Eigen::Map<const Eigen::VectorXd> w(N_VGetArrayPointer(m.ewt), m.n);
  const double e = h * std::sqrt(((f_new - f_old).array() * w.array()).square().sum() / m.n);
  return std::isfinite(e) ? e : kInf;
}

void CvodeIntegrator::setDifferenceJacobian(DifferenceJacobianFunction jacobian) {
  Impl& m = *impl_;
  if (m.initialized) throw InputError(m.prefix() + ": setDifferenceJacobian() must be called before initialize()");
  if (m.opts.method != Method::BDF) throw InputError(m.prefix() + ": a Jacobian is only used with Method::BDF");
  m.diff_jac = std::move(jacobian);
}

void CvodeIntegrator::setJacobianStructure(JacobianStructure structure) {
  Impl& m = *impl_;
  if (m.initialized) throw InputError(m.prefix() + ": setJacobianStructure() must be called before initialize()");
  if (m.opts.method != Method::BDF || m.opts.dense_solver != CvodeOptions::DenseSolver::Eigen)
    throw InputError(m.prefix() + ": a Jacobian structure needs Method::BDF with the Eigen dense solver");
  structure.validate(m.n);
  m.structure = std::move(structure);
}

void JacobianStructure::validate(int n) const {
  std::vector<int> seen(static_cast<size_t>(std::max(0, n)), 0);
  auto mark = [&](int i) {
    if (i < 0 || i >= n)
      throw InputError("Jacobian structure: state index " + std::to_string(i) + " outside 0.." + std::to_string(n - 1));
    if (seen[static_cast<size_t>(i)]++)
      throw InputError("Jacobian structure: state " + std::to_string(i) + " listed twice");
  };
  for (int i : hub) mark(i);
  for (const auto& b : blocks) {
    if (b.empty()) throw InputError("Jacobian structure: an empty block");
    for (int i : b) mark(i);
  }
  for (int i = 0; i < n; ++i)
    if (!seen[static_cast<size_t>(i)])
      throw InputError("Jacobian structure: state " + std::to_string(i) + " is in neither the hub nor a block");
  std::vector<char> in_hub(static_cast<size_t>(std::max(0, n)), 0);
  for (int i : hub) in_hub[static_cast<size_t>(i)] = 1;
  for (const auto* lists : {&block_hub_columns, &block_hub_rows}) {
    const char* what = lists == &block_hub_columns ? "block_hub_columns" : "block_hub_rows";
    if (lists->empty()) continue;
    if (lists->size() != blocks.size())
      throw InputError(std::string("Jacobian structure: ") + what + ": expected one list per block (" +
                       std::to_string(blocks.size()) + "), got " + std::to_string(lists->size()));
    for (const auto& list : *lists) {
      std::vector<char> listed(static_cast<size_t>(n), 0);
      for (int i : list) {
        if (i < 0 || i >= n || !in_hub[static_cast<size_t>(i)])
          throw InputError(std::string("Jacobian structure: ") + what + ": state " + std::to_string(i) +
                           " is not a hub state");
        if (listed[static_cast<size_t>(i)]++)
          throw InputError(std::string("Jacobian structure: ") + what + ": state " + std::to_string(i) +
                           " listed twice");
      }
    }
  }
}

bool CvodeIntegrator::rootFound() const { return impl_->root_found; }

const std::vector<int>& CvodeIntegrator::rootDirections() const { return impl_->root_dirs; }

CvodeOptions stiffDriveSolver(double rtol, double atol) {
  CvodeOptions o;
  o.method = Method::BDF;
  o.max_order = 2;
  o.rtol = rtol;
  o.atol = atol;
  return o;
}

}  // namespace jointsim::sim
