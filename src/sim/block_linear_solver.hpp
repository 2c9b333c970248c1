#pragma once
// Internal to the sim layer: the Eigen direct linear solver that CvodeIntegrator gives CVODE (block_linear_solver.cpp).
#include <Eigen/Core>

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

#include "jointsim/sim/cvode_integrator.hpp"

namespace jointsim::sim {

/// A matrix-based direct SUNLinearSolver over SUNDenseMatrix storage for n states: setup factorises the Newton matrix
/// with Eigen's partial-pivoting LU, or, when `structure` is not empty, by block elimination of its bordered
/// block-diagonal form (falling back to the dense LU for a block or Schur complement that is singular or
/// ill-conditioned); solve applies the factors without allocating. nullptr when SUNDIALS cannot allocate it.
SUNLinearSolver makeEigenDenseSolver(Eigen::Index n, SUNContext ctx, const JacobianStructure& structure);

}  // namespace jointsim::sim
