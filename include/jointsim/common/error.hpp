#pragma once
/// \file
/// Exception hierarchy of jointsim. Every error a user can cause derives from jointsim::Error, so a
/// caller (and the CLI) can catch one type. The CLI maps InputError to exit status 2,
/// UnidentifiableError to 3 and every other Error to exit status 1.

#include <exception>
#include <stdexcept>
#include <string>
#include <utility>

namespace jointsim {

/// Base class of all jointsim exceptions.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad user input: a configuration or robot file that does not parse or validate, a bad command-line
/// value, an argument of the wrong size. The message names the file, the key path (and line when the
/// parser gives one) and what was expected.
///
/// Structured: besides the message, an InputError carries where the bad value was, as far as the thrower
/// knows it: the file and line (file readers), and the key path ("friction.model.positive.alpha0",
/// "tau_pos[2]"). A parameter check (common/check.hpp) knows only the key path relative to its component;
/// a file reader that catches it re-throws it at that key's file and line (io::YamlValue::relocate), so a
/// message always points at the line to fix.
class InputError : public Error {
 public:
  /// An error without structure: what() is `message`.
  explicit InputError(const std::string& message) : Error(message), message_(message) {}
  /// what() = "FILE:LINE: KEY.PATH: MESSAGE" with the empty parts (and a line of 0) left out.
  InputError(std::string file, int line, std::string key_path, const std::string& message)
      : Error(compose(file, line, key_path, message)),
        file_(std::move(file)),
        key_path_(std::move(key_path)),
        message_(message),
        line_(line) {}
  /// An invalid parameter of a component, without a file: what() = "COMPONENT: KEY: MESSAGE"; keyPath() is the
  /// key (relative to the component's mapping), message() the rule ("expected a finite value > 0 N·m, got -1").
  static InputError parameter(const std::string& component, const std::string& key, const std::string& message) {
    InputError e(component + ": " + key + ": " + message);
    e.key_path_ = key;
    e.message_ = message;
    return e;
  }
  const std::string& file() const noexcept { return file_; }         ///< empty when unknown
  int line() const noexcept { return line_; }                        ///< 1-based; 0 when unknown
  const std::string& keyPath() const noexcept { return key_path_; }  ///< empty when unknown
  const std::string& message() const noexcept { return message_; }   ///< what() without the location
  /// True when the error names a file (it needs no relocation by a caller).
  bool located() const noexcept { return !file_.empty(); }
  /// A file that does not exist: what() = "PATH: MESSAGE"; missingPath() names it (Python raises a
  /// FileNotFoundError). Not located: a reader that named the file relocates it at its key. An InputError made while
  /// such an error is being handled (a caller adding where the file was named) is about the same missing file.
  static InputError fileNotFound(const std::string& path, const std::string& message) {
    InputError e(path + ": " + message);
    e.missing_path_ = path;
    return e;
  }
  bool missingFile() const noexcept { return !missing_path_.empty(); }
  const std::string& missingPath() const noexcept { return missing_path_; }

  static std::string compose(const std::string& file, int line, const std::string& key_path,
                             const std::string& message) {
    std::string s;
    if (!file.empty()) s += file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": ";
    if (!key_path.empty()) s += key_path + ": ";
    return s + message;
  }

 private:
  /// The missing file of the InputError being handled, if any (see fileNotFound).
  static std::string missingInFlight() {
    if (const std::exception_ptr p = std::current_exception()) {
      try {
        std::rethrow_exception(p);
      } catch (const InputError& e) {
        return e.missing_path_;
      } catch (...) {
      }
    }
    return {};
  }

  std::string file_, key_path_, message_;
  int line_ = 0;
  std::string missing_path_ = missingInFlight();
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
