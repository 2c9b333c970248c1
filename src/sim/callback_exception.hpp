#pragma once
// Internal to the sim layer: what an exception thrown by a user callback (right-hand side, Jacobian, root function)
// says, for the integrators' RHS_EXCEPTION errors (cvode_integrator.cpp, fixed_step_integrator.cpp).
#include <exception>
#include <string>

#include "jointsim/common/error.hpp"

namespace jointsim::sim {

/// The message of the exception `e`; a ComponentError's component replaces `component` (otherwise unchanged).
inline std::string callbackExceptionText(const std::exception_ptr& e, std::string& component) {
  try {
    std::rethrow_exception(e);
  } catch (const ComponentError& x) {
    component = x.component();
    return x.what();
  } catch (const std::exception& x) {
    return x.what();
  } catch (...) {
    return "unknown exception";
  }
}

}  // namespace jointsim::sim
