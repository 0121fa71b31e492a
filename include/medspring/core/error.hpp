// The typed exceptions of MedSpring, thrown at API boundaries (never inside an update loop).
#pragma once

#include <stdexcept>
#include <string>

namespace medspring {

/// Base of every MedSpring exception; what() is one line naming the offending file, element or path.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad user input: invalid mesh, negative stiffness, out-of-range index, NaN parameter, ...
class InvalidInput : public Error {
 public:
  using Error::Error;
};

/// A file could not be read or written (names the file, and the line where it applies).
class IoError : public Error {
 public:
  using Error::Error;
};

/// A numerical solve failed: singular system, no equilibrium, no convergence.
class SolverError : public Error {
 public:
  using Error::Error;
};

}  // namespace medspring
