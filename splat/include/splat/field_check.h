// Range checks for configuration structs' validate(): each failure throws splat::Error naming
// the field with its path, the allowed range and the value ("mapping.window: expected an integer
// >= 1, got 0"). NaN fails every check.
#pragma once
#include <sstream>
#include <string>
#include <type_traits>

#include "splat/error.h"

namespace splat {

class FieldCheck {
 public:
  explicit FieldCheck(std::string prefix) : prefix_(std::move(prefix)) {}

  template <typename T>
  void at_least(const char* name, T value, T min) const {
    if (!(value >= min)) fail(name, kind<T>() + " >= " + text(min), value);
  }
  template <typename T>
  void positive(const char* name, T value) const {
    if (!(value > T(0))) fail(name, kind<T>() + " > 0", value);
  }
  template <typename T>
  void in_range(const char* name, T value, T lo, T hi) const {
    if (!(value >= lo && value <= hi)) fail(name, kind<T>() + " in [" + text(lo) + ", " + text(hi) + "]", value);
  }
  // Anything else: `expected` says what was allowed.
  template <typename T>
  [[noreturn]] void fail(const std::string& name, const std::string& expected, const T& got) const {
    throw Error(prefix_ + name + ": expected " + expected + ", got " + text(got));
  }

 private:
  template <typename T>
  static std::string kind() {
    return std::is_integral_v<T> ? "an integer" : "a number";
  }
  template <typename T>
  static std::string text(const T& value) {
    std::ostringstream out;
    out << value;
    return out.str();
  }
  std::string prefix_;
};

}  // namespace splat
