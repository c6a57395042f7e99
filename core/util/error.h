#pragma once
// Typed errors. Each names what is at fault (file, JSON path, element) in its
// message; app/ maps the kind to a distinct process exit code.
#include <stdexcept>
#include <string>

namespace organsim {

enum class ErrorKind {
  Usage = 2,        // bad command line
  Input = 3,        // unreadable or invalid input file (mesh, scenario)
  Scenario = 4,     // scenario field missing, wrong type, out of range
  Numerical = 5,    // unstable step refused, blow-up detected during a run
  Backend = 6,      // GL/EGL context or shader failure
  Output = 7,       // cannot write an output
  Cases = 8,        // organsim sweep: some cases failed (each is recorded)
  SolverWarning = 9,  // organsim run: finished, but over 1 % of its implicit steps' solves stopped above their tolerance
  Interrupted = 130,  // organsim sweep: stopped by SIGINT/SIGTERM; unfinished cases stay pending
};

class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
  ErrorKind kind() const { return kind_; }
  int exit_code() const { return static_cast<int>(kind_); }

 private:
  ErrorKind kind_;
};

// "FILE: message" for input files.
inline Error input_error(const std::string& file, const std::string& message) {
  return Error(ErrorKind::Input, file + ": " + message);
}

}  // namespace organsim
