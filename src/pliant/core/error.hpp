// The error hierarchy. Module entry points validate their inputs and throw; per-element kernels
// never throw. The CLI catches at main and prints `pliant: error: <what>`.
//
//   Error
//   ├── InvalidInput   arguments or data that break a documented precondition (exit code 1)
//   ├── IoError        a file that cannot be opened, read, parsed or written (exit code 1)
//   ├── Unsupported    a valid request pliant does not implement (exit code 1)
//   └── InternalError  a broken invariant: a bug in pliant (PLIANT_CHECK failures)
//
// Interrupted (not an Error): a run stopped on its caller's request.
#pragma once

#include <stdexcept>
#include <string>

namespace pliant {

class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

class InvalidInput : public Error {
public:
    using Error::Error;
};

class IoError : public Error {
public:
    using Error::Error;
};

class Unsupported : public Error {
public:
    using Error::Error;
};

class InternalError : public Error {
public:
    using Error::Error;
};

// Not an error: a long run that its caller asked to stop (a keep-going callback returned false)
// stopped cleanly, its outputs consistent; what() says where they are. The CLI prints
// `pliant: interrupted: <what>` and exits with 130.
class Interrupted : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace pliant
