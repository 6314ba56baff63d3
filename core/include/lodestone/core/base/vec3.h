#pragma once
// A three-component vector usable on host and device. Standard layout (three
// contiguous scalars), so a host's interleaved xyz arrays map onto Vec3 arrays.
#include <cmath>

#include "lodestone/core/base/hostdev.h"

namespace lodestone {
inline namespace base {

template <typename T>
struct Vec3 {
  T x{}, y{}, z{};

  constexpr Vec3() = default;
  LODESTONE_HOSTDEV constexpr Vec3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
  template <typename U>
  LODESTONE_HOSTDEV constexpr explicit Vec3(const Vec3<U>& o)
      : x(static_cast<T>(o.x)), y(static_cast<T>(o.y)), z(static_cast<T>(o.z)) {}

  LODESTONE_HOSTDEV constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  LODESTONE_HOSTDEV constexpr const T& operator[](int i) const {
    return i == 0 ? x : (i == 1 ? y : z);
  }

  LODESTONE_HOSTDEV constexpr Vec3& operator+=(const Vec3& o) {
    x += o.x; y += o.y; z += o.z;
    return *this;
  }
  LODESTONE_HOSTDEV constexpr Vec3& operator-=(const Vec3& o) {
    x -= o.x; y -= o.y; z -= o.z;
    return *this;
  }
  LODESTONE_HOSTDEV constexpr Vec3& operator*=(T s) {
    x *= s; y *= s; z *= s;
    return *this;
  }
};

using Vec3d = Vec3<double>;
using Vec3f = Vec3<float>;

template <typename T>
LODESTONE_HOSTDEV constexpr Vec3<T> operator+(Vec3<T> a, const Vec3<T>& b) { return a += b; }
template <typename T>
LODESTONE_HOSTDEV constexpr Vec3<T> operator-(Vec3<T> a, const Vec3<T>& b) { return a -= b; }
template <typename T>
LODESTONE_HOSTDEV constexpr Vec3<T> operator-(const Vec3<T>& a) { return {-a.x, -a.y, -a.z}; }
template <typename T>
LODESTONE_HOSTDEV constexpr Vec3<T> operator*(Vec3<T> a, T s) { return a *= s; }
template <typename T>
LODESTONE_HOSTDEV constexpr Vec3<T> operator*(T s, Vec3<T> a) { return a *= s; }
template <typename T>
LODESTONE_HOSTDEV constexpr Vec3<T> operator/(const Vec3<T>& a, T s) {
  return {a.x / s, a.y / s, a.z / s};
}
template <typename T>
LODESTONE_HOSTDEV constexpr bool operator==(const Vec3<T>& a, const Vec3<T>& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}
template <typename T>
LODESTONE_HOSTDEV constexpr bool operator!=(const Vec3<T>& a, const Vec3<T>& b) {
  return !(a == b);
}

template <typename T>
LODESTONE_HOSTDEV constexpr T dot(const Vec3<T>& a, const Vec3<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <typename T>
LODESTONE_HOSTDEV constexpr Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T>
LODESTONE_HOSTDEV constexpr T norm2(const Vec3<T>& a) { return dot(a, a); }
template <typename T>
LODESTONE_HOSTDEV inline T norm(const Vec3<T>& a) {
  using std::abs;
  using std::isfinite;
  using std::sqrt;
  const T s = norm2(a);
  if (isfinite(s) && s > T(0)) return sqrt(s);
  if (s == T(0) && a.x == T(0) && a.y == T(0) && a.z == T(0)) return T(0);
  // The squares over- or underflowed: rescale by the largest component.
  T m = abs(a.x);
  if (abs(a.y) > m) m = abs(a.y);
  if (abs(a.z) > m) m = abs(a.z);
  if (!isfinite(m) || m == T(0)) return m;
  return m * sqrt(norm2(a / m));
}
template <typename T>
LODESTONE_HOSTDEV inline bool isFinite(const Vec3<T>& a) {
  using std::isfinite;
  return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}

}  // namespace base
}  // namespace lodestone
