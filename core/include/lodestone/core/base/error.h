#pragma once
// Exceptions thrown inside the C++ layers. Messages name the offending value
// and what was expected; the C ABI translates them into status codes.
#include <sstream>
#include <stdexcept>
#include <string>

#include "lodestone/core/base/number_text.h"

namespace lodestone {
inline namespace base {

/// Base of every Lodestone exception.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A caller passed a value outside its valid range (bad units, NaN, sizes...).
class InvalidArgument : public Error {
 public:
  using Error::Error;
};

namespace concat_parts {
template <typename T>
void appendOne(std::ostringstream& os, const T& v) {
  os << v;
}
inline void appendOne(std::ostringstream& os, double v) { os << numberText(v); }
inline void appendOne(std::ostringstream& os, float v) { os << numberText(v); }
inline void appendAll(std::ostringstream&) {}
template <typename Head, typename... Tail>
void appendAll(std::ostringstream& os, const Head& h, const Tail&... t) {
  appendOne(os, h);
  appendAll(os, t...);
}
}  // namespace concat_parts

/// Concatenates the arguments with operator<<; a double or float as the
/// shortest text that reads back as the same value (numberText: "0.4", not
/// "0.40000000000000002").
template <typename... Args>
std::string concat(const Args&... args) {
  std::ostringstream os;
  os.precision(17);
  concat_parts::appendAll(os, args...);
  return os.str();
}

/// Throws InvalidArgument with the concatenated message unless `ok`.
template <typename... Args>
void require(bool ok, const Args&... args) {
  if (!ok) throw InvalidArgument(concat(args...));
}

}  // namespace base
}  // namespace lodestone
