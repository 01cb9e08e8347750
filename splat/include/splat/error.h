#pragma once
#include <stdexcept>

namespace splat {

// The one error type of gslam's libraries: invalid input or a missing environment. Messages name
// the function (or file), the offending value, what was expected and what was got.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace splat
