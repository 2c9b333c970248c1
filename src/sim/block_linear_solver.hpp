#pragma once
// Internal to the sim layer: the Eigen direct linear solver that CvodeIntegrator gives CVODE (block_linear_solver.cpp).
#include <Eigen/Core>

#include <memory>
#include <vector>

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

#include "jointsim/sim/cvode_integrator.hpp"

namespace jointsim::sim {

/// A matrix-based direct SUNLinearSolver over SUNDenseMatrix storage for n states: setup factorises the Newton matrix
/// with Eigen's partial-pivoting LU, or, when `structure` is not empty, by block elimination of its bordered
/// block-diagonal form (falling back to the dense LU for a block or Schur complement that is singular or
/// ill-conditioned); solve applies the factors without allocating. nullptr when SUNDIALS cannot allocate it.
SUNLinearSolver makeEigenDenseSolver(Eigen::Index n, SUNContext ctx, const JacobianStructure& structure);

/// The entries of an n × n matrix inside `structure` (hub × hub, each block × itself, a block's rows × the hub columns
/// it may read, the hub rows it may act on × its columns) as runs of consecutive rows of one column, in column order:
/// what a plant Jacobian may write, so the only entries the Jacobian's zeroing, copies and scalings need to touch
/// (the others stay 0). Empty for an empty structure.
struct EntryRun {
  int col, row, len;
};
std::vector<EntryRun> structureRuns(const JacobianStructure& structure, int n);

/// The same direct solver without SUNDIALS (FixedStepIntegrator's I − γhJ): factor() then any number of solve()s, which
/// allocate nothing.
class DirectSolver {
 public:
  DirectSolver(Eigen::Index n, const JacobianStructure& structure);
  ~DirectSolver();
  DirectSolver(const DirectSolver&) = delete;
  DirectSolver& operator=(const DirectSolver&) = delete;
  /// Factorises A (n × n); false when it is singular (a zero pivot of the dense LU).
  bool factor(const Eigen::MatrixXd& A);
  /// Factorises A = I − c·J; with a structure without forming A (its entries outside the structure are not read).
  bool factorIdentityMinus(const Eigen::MatrixXd& J, double c);
  /// x = A⁻¹ b (b and x of size n; they may not alias).
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  /// The sign of det A of the last successful factor() or factorIdentityMinus(): +1 or −1 (the product of the pivots'
  /// signs and of the permutations' parities, over the blocks and the Schur complement: det A = Π det D_k · det S).
  int determinantSign() const;
  /// For factorisations that many solves reuse: with a structure, the blocks' and the Schur complement's inverses are
  /// formed when a factorisation serves its third solve (about 3 µs for the UR5 twin's six 14-state blocks), and
  /// solve() then multiplies by them instead of substituting (its results differ in the last bits). The dense fallback
  /// is unchanged.
  void useExplicitInverses();
  /// How many factorisations fell back from the block elimination to the dense LU (a block or the Schur complement
  /// singular or ill-conditioned).
  long denseFallbacks() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace jointsim::sim
