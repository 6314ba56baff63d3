#pragma once
// Small 3x3 matrices for host and device: a general (row-major) Mat3 for
// rotations and stresses, and a symmetric SymMat3 for magnetic Jacobian blocks.
#include "lodestone/core/base/hostdev.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace base {

template <typename T>
struct Mat3 {
  T m[3][3]{};

  LODESTONE_HOSTDEV static constexpr Mat3 identity() {
    Mat3 r;
    r.m[0][0] = r.m[1][1] = r.m[2][2] = T(1);
    return r;
  }
  LODESTONE_HOSTDEV static constexpr Mat3 diagonal(T a, T b, T c) {
    Mat3 r;
    r.m[0][0] = a;
    r.m[1][1] = b;
    r.m[2][2] = c;
    return r;
  }
  LODESTONE_HOSTDEV static constexpr Mat3 outer(const Vec3<T>& a, const Vec3<T>& b) {
    Mat3 r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.m[i][j] = a[i] * b[j];
    return r;
  }
  /// The cross-product matrix [w]x: [w]x v = w x v (the velocity gradient of a spin w).
  LODESTONE_HOSTDEV static constexpr Mat3 cross(const Vec3<T>& w) {
    Mat3 r;
    r.m[0][1] = -w.z;
    r.m[0][2] = w.y;
    r.m[1][0] = w.z;
    r.m[1][2] = -w.x;
    r.m[2][0] = -w.y;
    r.m[2][1] = w.x;
    return r;
  }
  LODESTONE_HOSTDEV constexpr T& operator()(int i, int j) { return m[i][j]; }
  LODESTONE_HOSTDEV constexpr const T& operator()(int i, int j) const { return m[i][j]; }

  LODESTONE_HOSTDEV constexpr Vec3<T> operator*(const Vec3<T>& v) const {
    return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
            m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
  }
  LODESTONE_HOSTDEV constexpr Mat3 operator*(const Mat3& o) const {
    Mat3 r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.m[i][j] = m[i][0] * o.m[0][j] + m[i][1] * o.m[1][j] + m[i][2] * o.m[2][j];
    return r;
  }
  LODESTONE_HOSTDEV constexpr Mat3 transposed() const {
    Mat3 r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.m[i][j] = m[j][i];
    return r;
  }
  /// Transpose times vector, i.e. R^T v (the inverse of a rotation applied to v).
  LODESTONE_HOSTDEV constexpr Vec3<T> transposeTimes(const Vec3<T>& v) const {
    return {m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z,
            m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
            m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z};
  }
};

using Mat3d = Mat3<double>;

/// Symmetric 3x3 matrix stored as (xx, yy, zz, xy, xz, yz).
template <typename T>
struct SymMat3 {
  T xx{}, yy{}, zz{}, xy{}, xz{}, yz{};

  LODESTONE_HOSTDEV static constexpr SymMat3 scaledIdentity(T s) {
    SymMat3 r;
    r.xx = r.yy = r.zz = s;
    return r;
  }
  /// a * I + b * h h^T
  LODESTONE_HOSTDEV static constexpr SymMat3 identityPlusOuter(T a, T b, const Vec3<T>& h) {
    SymMat3 r;
    r.xx = a + b * h.x * h.x;
    r.yy = a + b * h.y * h.y;
    r.zz = a + b * h.z * h.z;
    r.xy = b * h.x * h.y;
    r.xz = b * h.x * h.z;
    r.yz = b * h.y * h.z;
    return r;
  }
  LODESTONE_HOSTDEV constexpr Vec3<T> operator*(const Vec3<T>& v) const {
    return {xx * v.x + xy * v.y + xz * v.z, xy * v.x + yy * v.y + yz * v.z,
            xz * v.x + yz * v.y + zz * v.z};
  }
  LODESTONE_HOSTDEV constexpr SymMat3& operator+=(const SymMat3& o) {
    xx += o.xx; yy += o.yy; zz += o.zz; xy += o.xy; xz += o.xz; yz += o.yz;
    return *this;
  }
  LODESTONE_HOSTDEV constexpr SymMat3& operator*=(T s) {
    xx *= s; yy *= s; zz *= s; xy *= s; xz *= s; yz *= s;
    return *this;
  }
  LODESTONE_HOSTDEV constexpr T trace() const { return xx + yy + zz; }
};

using SymMat3d = SymMat3<double>;

}  // namespace base
}  // namespace lodestone
