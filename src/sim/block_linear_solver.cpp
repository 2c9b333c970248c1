// The Eigen direct linear solver behind CVODE's Newton iteration (a SUNLinearSolver): dense partial-pivoting LU, or
// block elimination of a bordered block-diagonal Newton matrix (sim::JacobianStructure). Apart from the CVODE wrapper
// (cvode_integrator.cpp), which only plugs it in.
#include "sim/block_linear_solver.hpp"

#include <Eigen/LU>

#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

namespace jointsim::sim {

namespace {

// ------------------------------------------------------------------ Eigen dense linear solver
// A SUNLinearSolver (matrix-based, direct) over SUNDenseMatrix storage: setup factorises the Newton
// matrix with Eigen::PartialPivLU (blocked, vectorised), solve applies it. The solves allocate nothing.

/// x = A⁻¹ x with A = P⁻¹ L U from `f` (x holds b on entry), by column-oriented substitution (the dense fallback of
/// DirectSolver): for up to a hundred states a plain loop over contiguous columns is several times faster than
/// Eigen's blocked triangular solver, whose panel logic is tuned for large matrices.
void luSolveInPlace(const Eigen::PartialPivLU<Eigen::MatrixXd>& f, Eigen::VectorXd& x, Eigen::VectorXd& work) {
  const Eigen::MatrixXd& lu = f.matrixLU();
  const Eigen::Index m = lu.rows();
  const int* __restrict perm = f.permutationP().indices().data();
  const double* __restrict a = lu.data();
  double* __restrict w = work.data();
  const double* __restrict b = x.data();
  for (Eigen::Index i = 0; i < m; ++i) w[perm[i]] = b[i];  // w = P b
  for (Eigen::Index j = 0; j < m; ++j) {                   // L (unit lower)
    const double wj = w[j];
    const double* __restrict col = a + j * m;
    for (Eigen::Index i = j + 1; i < m; ++i) w[i] -= col[i] * wj;
  }
  for (Eigen::Index j = m - 1; j >= 0; --j) {  // U
    const double* __restrict col = a + j * m;
    const double wj = w[j] / col[j];
    w[j] = wj;
    for (Eigen::Index i = 0; i < j; ++i) w[i] -= col[i] * wj;
  }
  x.swap(work);
}

/// sign(det A) of A = P⁻¹ L U: the permutation's parity (inside Eigen's determinant()) times the signs of U's
/// diagonal. The product itself may overflow to ±inf, which keeps its sign; the pivots are non-zero (checked).
int luSign(const Eigen::PartialPivLU<Eigen::MatrixXd>& f) {
  if (f.rows() == 0) return 1;
  return f.determinant() < 0.0 ? -1 : 1;
}

/// Partial-pivoting LU of a small dense matrix in place, A = P⁻¹ L U (L unit lower, U upper), for the drive blocks
/// and the hub's Schur complement of a BlockPlan (10–20 states). Eigen's PartialPivLU spends most of its time at these
/// sizes in the set-up of its expressions per column; a plain right-looking elimination over contiguous columns that
/// skips the zero entries of the sparse blocks I − γhJ is cheaper. The arithmetic is Eigen's (unblocked_lu, used
/// below 16 rows): the pivot is the first largest magnitude of the column, the column is divided by it, the trailing
/// matrix gets a − l·u, and the substitutions divide by U's diagonal. Skipping a zero multiplier leaves an entry as
/// a − l·0 would, so up to 16 rows the factors and solutions are bit for bit Eigen's: the outputs of the shipped UR5,
/// RobotR3 and replay experiments (CVODE and fixed step) were compared byte for byte before and after.
struct SmallLu {
  Eigen::MatrixXd a;     // the matrix to factorise (filled by the caller), then L and U
  std::vector<int> piv;  // at step k, row k was swapped with row piv[k] (LAPACK's ipiv, 0-based)
  int sign = 1;          // sign(det A): the permutation's parity times the signs of the pivots

  void resize(Eigen::Index m) {
    a.resize(m, m);
    piv.assign(static_cast<size_t>(m), 0);
  }

  /// Factorises `a` in place. False when a pivot is zero or not finite, a multiplier is not finite, or the smallest
  /// pivot magnitude is below 1e-13 of the largest (a lower bound of the condition number: such a matrix is at least
  /// that ill-conditioned). A cheap test in place of a condition estimate, which cost 10 % of a sampled-control run;
  /// an ill-conditioned block that passes only slows CVODE's Newton iteration (its residual is the right-hand side
  /// itself), which it answers with a fresh Jacobian or a smaller step.
  bool factor() {
    const Eigen::Index m = a.rows();
    double* __restrict d = a.data();
    double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
    double multipliers = 0.0;  // Σ|l_ik| ≤ m²: finite unless an entry is NaN or ±∞ (which a skipped zero multiplier
                               // would otherwise leave in L unseen)
    sign = 1;
    for (Eigen::Index k = 0; k < m; ++k) {
      double* __restrict ck = d + k * m;
      Eigen::Index p = k;
      double best = std::abs(ck[k]);
      for (Eigen::Index i = k + 1; i < m; ++i)
        if (std::abs(ck[i]) > best) {
          best = std::abs(ck[i]);
          p = i;
        }
      if (!(best > 0.0) || !std::isfinite(best)) return false;
      piv[static_cast<size_t>(k)] = static_cast<int>(p);
      if (p != k) {
        sign = -sign;
        for (Eigen::Index j = 0; j < m; ++j) std::swap(d[j * m + k], d[j * m + p]);
      }
      if (ck[k] < 0.0) sign = -sign;
      lo = std::min(lo, best);
      hi = std::max(hi, best);
      const double pivot = ck[k];
      for (Eigen::Index i = k + 1; i < m; ++i) {
        ck[i] /= pivot;
        multipliers += std::abs(ck[i]);
      }
      for (Eigen::Index j = k + 1; j < m; ++j) {
        double* __restrict cj = d + j * m;
        const double u = cj[k];
        if (u == 0.0) continue;
        for (Eigen::Index i = k + 1; i < m; ++i) cj[i] -= ck[i] * u;
      }
    }
    return lo > 1e-13 * hi && std::isfinite(multipliers);
  }

  /// x = A⁻¹ x (x holds b on entry, m entries) with the factors of the last factor() that returned true.
  void solveInPlace(double* __restrict x) const {
    const Eigen::Index m = a.rows();
    const double* __restrict d = a.data();
    for (Eigen::Index k = 0; k < m; ++k) {
      const int p = piv[static_cast<size_t>(k)];
      if (p != k) std::swap(x[k], x[p]);
    }
    for (Eigen::Index j = 0; j < m; ++j) {  // L (unit lower)
      const double xj = x[j];
      if (xj == 0.0) continue;
      const double* __restrict col = d + j * m;
      for (Eigen::Index i = j + 1; i < m; ++i) x[i] -= col[i] * xj;
    }
    for (Eigen::Index j = m - 1; j >= 0; --j) {  // U
      const double* __restrict col = d + j * m;
      const double xj = x[j] / col[j];
      x[j] = xj;
      if (xj == 0.0) continue;
      for (Eigen::Index i = 0; i < j; ++i) x[i] -= col[i] * xj;
    }
  }
};

/// Block elimination of a bordered block-diagonal matrix A (JacobianStructure): with H the hub and B_k the blocks,
///   D_k = A(B_k, B_k), C_k = A(B_k, H), E_k = A(H, B_k), W_k = D_k⁻¹ C_k, S = A(H, H) − Σ E_k W_k,
/// and A x = b is solved by z_k = D_k⁻¹ b_k, x_H = S⁻¹ (b_H − Σ E_k z_k), x_k = z_k − W_k x_H.
/// A part usually couples to few hub states (a drive to its own joint's angle and rate): only the non-zero columns
/// Z_k of C_k enter W_k and the update of S (columns Z_k only), found at each factorisation. The blocks and S are
/// kept as LU factors (SmallLu; no inverses): for 14-state drive blocks against a 12-state hub this makes a
/// factorisation about three times cheaper than inverting, which matters where setups are frequent (sampled control
/// stops at every sample; each stop and restart changes the step and thus the Newton matrix; the fixed-step method
/// factorises at every step). Every workspace is sized once here.
///
/// With the structure's optional lists, only the declared hub columns of C_k are read (the candidates for Z_k) and
/// only the declared hub rows of E_k are kept (E_k is stored as those rows, `erows`): for a drive that reads its own
/// joint and acts on the n accelerations this reads 2m + nm entries per block instead of 4nm, and the updates of S
/// and of the solve's hub right-hand side touch n rows instead of 2n.
struct BlockPlan {
  explicit BlockPlan(const JacobianStructure& st) : hub(st.hub), blocks(st.blocks) {
    const auto h = static_cast<Eigen::Index>(hub.size());
    int largest = -1;
    for (int s : hub) largest = std::max(largest, s);
    std::vector<Eigen::Index> position(static_cast<size_t>(largest + 1), -1);
    for (Eigen::Index i = 0; i < h; ++i) position[static_cast<size_t>(hub[static_cast<size_t>(i)])] = i;
    auto positions = [&](const std::vector<std::vector<int>>& lists, size_t k) {
      std::vector<Eigen::Index> p;
      if (lists.empty()) {
        for (Eigen::Index i = 0; i < h; ++i) p.push_back(i);
      } else {
        for (int s : lists[k]) p.push_back(position[static_cast<size_t>(s)]);
        std::sort(p.begin(), p.end());
      }
      return p;
    };
    for (size_t k = 0; k < blocks.size(); ++k) {
      const auto m = static_cast<Eigen::Index>(blocks[k].size());
      ccand.push_back(positions(st.block_hub_columns, k));
      erows.push_back(positions(st.block_hub_rows, k));
      C.emplace_back(Eigen::MatrixXd::Zero(m, h));
      W.emplace_back(m, h);
      E.emplace_back(static_cast<Eigen::Index>(erows.back().size()), m);
      ez.emplace_back(static_cast<Eigen::Index>(erows.back().size()));
      lu.emplace_back().resize(m);
      z.emplace_back(m);
      cols.emplace_back();
      cols.back().reserve(static_cast<size_t>(h));
    }
    luS.resize(h);
    r.resize(h);
    xr.resize(h);
  }

  void useExplicitInverses() {
    explicit_inverses = true;
    Dinv.clear();
    bk.clear();
    for (const auto& B : blocks) {
      const auto m = static_cast<Eigen::Index>(B.size());
      Dinv.emplace_back(m, m);
      bk.emplace_back(m);
    }
    Sinv.resize(static_cast<Eigen::Index>(hub.size()), static_cast<Eigen::Index>(hub.size()));
  }

  /// The inverse of a factorised matrix, column by column: A⁻¹ e_j.
  static void invert(const SmallLu& f, Eigen::MatrixXd& out) {
    out.setIdentity();
    for (Eigen::Index j = 0; j < out.cols(); ++j) f.solveInPlace(out.col(j).data());
  }
  std::vector<int> hub;
  std::vector<std::vector<int>> blocks;
  std::vector<Eigen::MatrixXd> C, W;
  std::vector<Eigen::MatrixXd> E;  // E_k's rows erows[k] (the others are zero)
  std::vector<SmallLu> lu;         // D_k, then its factors
  std::vector<Eigen::VectorXd> z, ez;
  std::vector<std::vector<Eigen::Index>> cols;   // Z_k: the hub columns where C_k is not zero
  std::vector<std::vector<Eigen::Index>> ccand;  // the hub columns C_k may be non-zero in (positions in hub)
  std::vector<std::vector<Eigen::Index>> erows;  // the hub rows E_k may be non-zero in (positions in hub)
  SmallLu luS;                                   // S, then its factors
  Eigen::VectorXd r, xr;
  // With explicit_inverses (set for factorisations that many solves reuse: the fixed step's kept Jacobian), D_k⁻¹
  // and S⁻¹ are formed once a factorisation serves its third solve (a step's two solves do not pay for them: the
  // growing-mode probes and short-lived Jacobians keep substituting), and a solve is then matrix–vector products
  // without the substitutions' chains of dependent divisions. Its results differ from the substitutions' in the last
  // bits.
  bool explicit_inverses = false;
  bool inverses_formed = false;
  int solves_since_factor = 0;
  std::vector<Eigen::MatrixXd> Dinv;
  Eigen::MatrixXd Sinv;
  std::vector<Eigen::VectorXd> bk;  // b's block k

  /// sign(det A) = Π sign(det D_k) · sign(det S).
  int determinantSign() const {
    int sign = luS.sign;
    for (const auto& f : lu) sign *= f.sign;
    return sign;
  }

  /// Factorises A (column-major n × n); false when a block or the Schur complement is unusable.
  bool factor(const Eigen::Map<const Eigen::MatrixXd>& A) {
    return factorEntries([&A](int i, int j) { return A(i, j); });
  }

  /// Factorises A = I − c·J without forming it (only the structure's entries are read).
  bool factorIdentityMinus(const Eigen::MatrixXd& J, double c) {
    return factorEntries([&J, c](int i, int j) { return (i == j ? 1.0 : 0.0) - c * J(i, j); });
  }

  /// The factorisation, reading A(i, j) through `A`.
  template <class Entry>
  bool factorEntries(const Entry& A) {
    inverses_formed = false;  // (also when this factorisation fails: the blocks' factors are overwritten)
    solves_since_factor = 0;
    const size_t nb = blocks.size();
    const auto h = static_cast<Eigen::Index>(hub.size());
    Eigen::MatrixXd& S = luS.a;
    for (Eigen::Index j = 0; j < h; ++j)
      for (Eigen::Index i = 0; i < h; ++i) S(i, j) = A(hub[static_cast<size_t>(i)], hub[static_cast<size_t>(j)]);
    for (size_t k = 0; k < nb; ++k) {
      const auto& B = blocks[k];
      const auto m = static_cast<Eigen::Index>(B.size());
      Eigen::MatrixXd& D = lu[k].a;
      for (Eigen::Index j = 0; j < m; ++j)
        for (Eigen::Index i = 0; i < m; ++i) D(i, j) = A(B[static_cast<size_t>(i)], B[static_cast<size_t>(j)]);
      if (!lu[k].factor()) return false;
      cols[k].clear();
      for (Eigen::Index j : ccand[k]) {
        bool nonzero = false;
        for (Eigen::Index i = 0; i < m; ++i) {
          C[k](i, j) = A(B[static_cast<size_t>(i)], hub[static_cast<size_t>(j)]);
          nonzero = nonzero || C[k](i, j) != 0.0;
        }
        if (nonzero) cols[k].push_back(j);
      }
      const auto& er = erows[k];
      const auto ne = static_cast<Eigen::Index>(er.size());
      for (Eigen::Index j = 0; j < m; ++j)
        for (Eigen::Index i = 0; i < ne; ++i)
          E[k](i, j) = A(hub[static_cast<size_t>(er[static_cast<size_t>(i)])], B[static_cast<size_t>(j)]);
      for (Eigen::Index j : cols[k]) {
        z[k] = C[k].col(j);
        lu[k].solveInPlace(z[k].data());
        W[k].col(j) = z[k];
        ez[k].noalias() = E[k] * z[k];
        for (Eigen::Index i = 0; i < ne; ++i) S(er[static_cast<size_t>(i)], j) -= ez[k][i];
      }
    }
    return luS.factor();
  }

  /// Solves with the factors formed at setup. CVODE's Newton iteration evaluates its residual with the
  /// right-hand side itself, so the last bits of the solve only affect its convergence rate, not the accuracy of
  /// the step.
  void solve(const double* b, double* x) {
    const size_t nb = blocks.size();
    const auto h = static_cast<Eigen::Index>(hub.size());
    if (explicit_inverses && !inverses_formed && ++solves_since_factor > 2) {
      for (size_t k = 0; k < nb; ++k) invert(lu[k], Dinv[k]);
      invert(luS, Sinv);
      inverses_formed = true;
    }
    const bool by_inverses = inverses_formed;
    for (Eigen::Index i = 0; i < h; ++i) r[i] = b[hub[static_cast<size_t>(i)]];
    for (size_t k = 0; k < nb; ++k) {
      const auto& B = blocks[k];
      if (by_inverses) {
        for (size_t i = 0; i < B.size(); ++i) bk[k][static_cast<Eigen::Index>(i)] = b[B[i]];
        z[k].noalias() = Dinv[k] * bk[k];
      } else {
        for (size_t i = 0; i < B.size(); ++i) z[k][static_cast<Eigen::Index>(i)] = b[B[i]];
        lu[k].solveInPlace(z[k].data());
      }
      ez[k].noalias() = E[k] * z[k];
      const auto& er = erows[k];
      for (size_t i = 0; i < er.size(); ++i) r[er[i]] -= ez[k][static_cast<Eigen::Index>(i)];
    }
    if (by_inverses) {
      xr.noalias() = Sinv * r;
    } else {
      xr = r;
      luS.solveInPlace(xr.data());
    }
    for (Eigen::Index i = 0; i < h; ++i) x[hub[static_cast<size_t>(i)]] = xr[i];
    for (size_t k = 0; k < nb; ++k) {
      const auto& B = blocks[k];
      for (Eigen::Index j : cols[k]) z[k] -= W[k].col(j) * xr[j];
      for (size_t i = 0; i < B.size(); ++i) x[B[i]] = z[k][static_cast<Eigen::Index>(i)];
    }
  }
};

struct EigenDenseContent {
  explicit EigenDenseContent(Eigen::Index n) : lu(n), rhs(n) {}
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;
  Eigen::VectorXd rhs;
  sunindextype last_flag = 0;
  std::unique_ptr<BlockPlan> plan;  // block elimination (JacobianStructure); null: dense LU
  bool blocks_factored = false;     // the last setup used the plan (else the dense LU)
  long dense_fallbacks = 0;
  std::vector<EntryRun> runs;  // with a plan: the structure's entries (structureRuns), all the dense fallback reads
  Eigen::MatrixXd fallback;    // with a plan: the dense fallback's matrix

  void usePlan(const JacobianStructure& structure, Eigen::Index n) {
    plan = std::make_unique<BlockPlan>(structure);
    runs = structureRuns(structure, static_cast<int>(n));
    fallback.setZero(n, n);
  }

  /// With a plan, the matrix the dense fallback factorises: scale·A(i, j) + shift·δ_ij inside the structure and 0
  /// outside it, i.e. the matrix the block elimination reads. Whatever a Jacobian left outside its structure (where
  /// the structured zeroing and scaling do not reach) is thus ignored by both, as documented.
  const Eigen::MatrixXd& fallbackMatrix(const double* A, double scale, double shift) {
    const Eigen::Index n = fallback.rows();
    double* d = fallback.data();
    for (const EntryRun& r : runs) {
      const Eigen::Index at = static_cast<Eigen::Index>(r.col) * n + r.row;
      for (int i = 0; i < r.len; ++i) d[at + i] = scale * A[at + i];
    }
    fallback.diagonal().array() += shift;  // (the diagonal lies in the structure)
    return fallback;
  }
};

EigenDenseContent* eigenContent(SUNLinearSolver S) { return static_cast<EigenDenseContent*>(S->content); }

SUNLinearSolver_Type eigenGetType(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID eigenGetId(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int eigenInitialize(SUNLinearSolver) { return SUNLS_SUCCESS; }
int eigenSetup(SUNLinearSolver S, SUNMatrix A) {
  EigenDenseContent* c = eigenContent(S);
  const auto n = static_cast<Eigen::Index>(SM_ROWS_D(A));
  if (c->plan) {
    c->blocks_factored = c->plan->factor(Eigen::Map<const Eigen::MatrixXd>(SM_DATA_D(A), n, n));
    if (c->blocks_factored) {
      c->last_flag = 0;
      return SUNLS_SUCCESS;
    }
    ++c->dense_fallbacks;
    c->lu.compute(c->fallbackMatrix(SM_DATA_D(A), 1.0, 0.0));
  } else {
    c->lu.compute(Eigen::Map<const Eigen::MatrixXd>(SM_DATA_D(A), n, n));
  }
  // A zero pivot means a singular Newton matrix: report it as recoverable, as SUNLinSol_Dense does.
  const auto& m = c->lu.matrixLU();
  for (Eigen::Index k = 0; k < n; ++k)
    if (m(k, k) == 0.0) {
      c->last_flag = k + 1;
      return static_cast<int>(k + 1);
    }
  c->last_flag = 0;
  return SUNLS_SUCCESS;
}
int eigenSolve(SUNLinearSolver S, SUNMatrix A, N_Vector x, N_Vector b, realtype) {
  EigenDenseContent* c = eigenContent(S);
  const auto n = static_cast<Eigen::Index>(SM_ROWS_D(A));
  if (c->plan && c->blocks_factored) {
    c->plan->solve(N_VGetArrayPointer(b), N_VGetArrayPointer(x));
    c->last_flag = 0;
    return SUNLS_SUCCESS;
  }
  c->rhs = Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(b), n);
  Eigen::Map<Eigen::VectorXd> xm(N_VGetArrayPointer(x), n);
  xm.noalias() = c->lu.solve(c->rhs);
  c->last_flag = 0;
  return SUNLS_SUCCESS;
}
sunindextype eigenLastFlag(SUNLinearSolver S) { return eigenContent(S)->last_flag; }
int eigenFree(SUNLinearSolver S) {
  if (S == nullptr) return SUNLS_SUCCESS;
  delete eigenContent(S);
  S->content = nullptr;
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}

}  // namespace

/// The dense partial-pivoting LU of A into c.lu; false at a zero or non-finite pivot.
static bool denseFactor(EigenDenseContent& c, const Eigen::MatrixXd& A) {
  c.lu.compute(A);
  const auto& m = c.lu.matrixLU();
  for (Eigen::Index k = 0; k < m.rows(); ++k)
    if (!(m(k, k) != 0.0) || !std::isfinite(m(k, k))) return false;
  return true;
}

struct DirectSolver::Impl {
  // The content's type is local to this file: held type-erased (a field of it would give Impl internal linkage).
  Impl(Eigen::Index n, const JacobianStructure& structure) : holder(std::make_shared<EigenDenseContent>(n)), work(n) {
    if (!structure.empty()) content().usePlan(structure, n);
  }
  EigenDenseContent& content() { return *static_cast<EigenDenseContent*>(holder.get()); }
  std::shared_ptr<void> holder;
  Eigen::VectorXd work;
  Eigen::MatrixXd dense;  // I − cJ without a structure (factorIdentityMinus)
};

DirectSolver::DirectSolver(Eigen::Index n, const JacobianStructure& structure)
    : impl_(std::make_unique<Impl>(n, structure)) {}
DirectSolver::~DirectSolver() = default;

bool DirectSolver::factor(const Eigen::MatrixXd& A) {
  EigenDenseContent& c = impl_->content();
  if (c.plan) {
    c.blocks_factored = c.plan->factor(Eigen::Map<const Eigen::MatrixXd>(A.data(), A.rows(), A.cols()));
    if (c.blocks_factored) return true;
    ++c.dense_fallbacks;
    return denseFactor(c, c.fallbackMatrix(A.data(), 1.0, 0.0));
  }
  return denseFactor(c, A);
}

void DirectSolver::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  EigenDenseContent& c = impl_->content();
  if (c.plan && c.blocks_factored) {
    c.plan->solve(b.data(), x.data());
    return;
  }
  x = b;
  luSolveInPlace(c.lu, x, impl_->work);
}

bool DirectSolver::factorIdentityMinus(const Eigen::MatrixXd& J, double c) {
  EigenDenseContent& c_ = impl_->content();
  if (c_.plan) {
    c_.blocks_factored = c_.plan->factorIdentityMinus(J, c);
    if (c_.blocks_factored) return true;
    ++c_.dense_fallbacks;
    return denseFactor(c_, c_.fallbackMatrix(J.data(), -c, 1.0));
  }
  impl_->dense = -c * J;
  impl_->dense.diagonal().array() += 1.0;
  return denseFactor(c_, impl_->dense);
}

void DirectSolver::useExplicitInverses() {
  EigenDenseContent& c = *static_cast<EigenDenseContent*>(impl_->holder.get());
  if (c.plan) c.plan->useExplicitInverses();
}

long DirectSolver::denseFallbacks() const {
  return static_cast<const EigenDenseContent*>(impl_->holder.get())->dense_fallbacks;
}

int DirectSolver::determinantSign() const {
  const EigenDenseContent& c = *static_cast<const EigenDenseContent*>(impl_->holder.get());
  if (c.plan && c.blocks_factored) return c.plan->determinantSign();
  return luSign(c.lu);
}

std::vector<EntryRun> structureRuns(const JacobianStructure& st, int n) {
  std::vector<EntryRun> runs;
  if (st.empty()) return runs;
  std::vector<std::vector<int>> rows(static_cast<size_t>(n));
  for (int j : st.hub) {
    rows[static_cast<size_t>(j)] = st.hub;
    for (size_t k = 0; k < st.blocks.size(); ++k) {
      const bool reads =
          st.block_hub_columns.empty() ||
          std::find(st.block_hub_columns[k].begin(), st.block_hub_columns[k].end(), j) != st.block_hub_columns[k].end();
      if (reads)
        rows[static_cast<size_t>(j)].insert(rows[static_cast<size_t>(j)].end(), st.blocks[k].begin(),
                                            st.blocks[k].end());
    }
  }
  for (size_t k = 0; k < st.blocks.size(); ++k)
    for (int j : st.blocks[k]) {
      rows[static_cast<size_t>(j)] = st.blocks[k];
      const std::vector<int>& hub_rows = st.block_hub_rows.empty() ? st.hub : st.block_hub_rows[k];
      rows[static_cast<size_t>(j)].insert(rows[static_cast<size_t>(j)].end(), hub_rows.begin(), hub_rows.end());
    }
  for (int j = 0; j < n; ++j) {
    std::vector<int>& r = rows[static_cast<size_t>(j)];
    std::sort(r.begin(), r.end());
    for (size_t i = 0; i < r.size();) {
      size_t e = i + 1;
      while (e < r.size() && r[e] == r[e - 1] + 1) ++e;
      runs.push_back({j, r[i], static_cast<int>(e - i)});
      i = e;
    }
  }
  return runs;
}

SUNLinearSolver makeEigenDenseSolver(Eigen::Index n, SUNContext ctx, const JacobianStructure& structure) {
  SUNLinearSolver S = SUNLinSolNewEmpty(ctx);
  if (S == nullptr) return nullptr;
  S->ops->gettype = eigenGetType;
  S->ops->getid = eigenGetId;
  S->ops->initialize = eigenInitialize;
  S->ops->setup = eigenSetup;
  S->ops->solve = eigenSolve;
  S->ops->lastflag = eigenLastFlag;
  S->ops->free = eigenFree;
  auto* content = new EigenDenseContent(n);
  if (!structure.empty()) content->usePlan(structure, n);
  S->content = content;
  return S;
}

}  // namespace jointsim::sim
