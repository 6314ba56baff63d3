#pragma once
// Eigen-decomposition of a symmetric 3x3 matrix, A = Q diag(lambda) Q^T, for
// host and device (no exceptions, no allocation), by the cyclic Jacobi method
// (Golub and Van Loan 2013, Sec. 8.5; the rotation of Numerical Recipes 3rd
// ed., Eqs. 11.1.8-11.1.18). Jacobi is chosen over the closed-form cubic
// roots because it keeps full relative accuracy of small eigenvalues beside
// large ones and gives orthonormal vectors for repeated eigenvalues, which is
// what the principal (Hencky) strains of a nearly undeformed material need.
// Converges quadratically: 3-5 sweeps reach round-off in double; at most
// kJacobiMaxSweeps sweeps are taken, so a non-finite input returns
// non-finite values instead of looping.
#include <cmath>

#include "lodestone/core/base/hostdev.h"
#include "lodestone/core/base/mat3.h"

namespace lodestone {
inline namespace base {

/// Upper bound on the Jacobi sweeps (each sweep: the three off-diagonal pairs).
inline constexpr int kJacobiMaxSweeps = 24;

template <typename T>
struct SymmetricEigen3 {
  T values[3];       ///< eigenvalues, unsorted
  Mat3<T> vectors;   ///< orthonormal eigenvectors as columns: A = vectors diag(values) vectors^T
};

/// Eigen-decomposition of the symmetric part (A + A^T)/2 of A.
template <typename T>
LODESTONE_HOSTDEV inline SymmetricEigen3<T> symmetricEigen(const Mat3<T>& A) {
  using std::abs;
  using std::sqrt;
  Mat3<T> a;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a(i, j) = T(0.5) * (A(i, j) + A(j, i));
  Mat3<T> q = Mat3<T>::identity();
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int sweep = 0; sweep < kJacobiMaxSweeps; ++sweep) {
    if (a(0, 1) == T(0) && a(0, 2) == T(0) && a(1, 2) == T(0)) break;
    for (const auto& pq : pairs) {
      const int p = pq[0], r = pq[1];
      const T apr = a(p, r);
      if (apr == T(0)) continue;
      // An off-diagonal entry below round-off of both diagonal entries is
      // dropped (Numerical Recipes' test): the eigenvalues are then exact to
      // round-off, and the loop ends a sweep earlier than by exact zeros.
      const T g = T(100) * abs(apr);
      if (abs(a(p, p)) + g == abs(a(p, p)) && abs(a(r, r)) + g == abs(a(r, r))) {
        a(p, r) = a(r, p) = T(0);
        continue;
      }
      // Rotation P with P_pp = P_rr = c, P_pr = s, P_rp = -s zeroing a_pr in P^T a P.
      const T theta = (a(r, r) - a(p, p)) / (T(2) * apr);
      T t = T(1) / (abs(theta) + sqrt(theta * theta + T(1)));
      if (theta < T(0)) t = -t;
      const T c = T(1) / sqrt(t * t + T(1)), s = t * c;
      for (int k = 0; k < 3; ++k) {  // a <- a P (columns p and r)
        const T akp = a(k, p), akr = a(k, r);
        a(k, p) = c * akp - s * akr;
        a(k, r) = s * akp + c * akr;
      }
      for (int k = 0; k < 3; ++k) {  // a <- P^T a (rows p and r)
        const T apk = a(p, k), ark = a(r, k);
        a(p, k) = c * apk - s * ark;
        a(r, k) = s * apk + c * ark;
      }
      a(p, r) = a(r, p) = T(0);
      for (int k = 0; k < 3; ++k) {  // q <- q P
        const T qkp = q(k, p), qkr = q(k, r);
        q(k, p) = c * qkp - s * qkr;
        q(k, r) = s * qkp + c * qkr;
      }
    }
  }
  SymmetricEigen3<T> out;
  for (int i = 0; i < 3; ++i) out.values[i] = a(i, i);
  out.vectors = q;
  return out;
}

}  // namespace base
}  // namespace lodestone
