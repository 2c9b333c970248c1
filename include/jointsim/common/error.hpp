#pragma once
/// \file
/// Exception hierarchy of jointsim. Every error a user can cause derives from jointsim::Error, so a
/// caller (and the CLI) can catch one type. The CLI maps InputError to exit status 2,
/// UnidentifiableError to 3 and every other Error to exit status 1.

#include <stdexcept>
#include <string>

namespace jointsim {

/// Base class of all jointsim exceptions.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad user input: a configuration or robot file that does not parse or validate, a bad command-line
/// value, an argument of the wrong size. The message names the file, the key path (and line when the
/// parser gives one) and what was expected.
class InputError : public Error {
 public:
  using Error::Error;
};

/// Data that parse and validate but cannot determine a requested quantity (e.g. a clamping curve that
/// never crosses zero torque, so the backlash is unobservable). The CLI maps it to exit status 3.
class UnidentifiableError : public Error {
 public:
  using Error::Error;
};

/// A failure of the numerical integrator or of a component's right-hand side during a simulation. The
/// message says the simulated time, the solver flag and, where known, the component involved.
class SolverError : public Error {
 public:
  SolverError(const std::string& message, double time, std::string flag, std::string component = {})
      : Error(message), time_(time), flag_(std::move(flag)), component_(std::move(component)) {}
  /// Simulated time at which the failure happened [s].
  double time() const noexcept { return time_; }
  /// Name of the CVODE return flag (e.g. "CV_CONV_FAILURE"), or "RHS_EXCEPTION".
  const std::string& flag() const noexcept { return flag_; }
  /// Component that failed, if known (empty otherwise).
  const std::string& component() const noexcept { return component_; }

 private:
  double time_;
  std::string flag_;
  std::string component_;
};

/// Thrown from a right-hand side by a component that cannot evaluate its derivatives (e.g. a state out
/// of its physical range). The integrator turns it into a SolverError naming the component.
class ComponentError : public Error {
 public:
  ComponentError(std::string component, const std::string& message)
      : Error(component + ": " + message), component_(std::move(component)) {}
  const std::string& component() const noexcept { return component_; }

 private:
  std::string component_;
};

}  // namespace jointsim
