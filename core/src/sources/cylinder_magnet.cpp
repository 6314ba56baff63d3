#include "lodestone/core/sources/cylinder_magnet.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/sources/elliptic_integral.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace sources {

namespace {

double checkedPositive(double v, const char* what) {
  require(std::isfinite(v) && v > 0, "cylinder magnet: ", what,
          " must be a positive finite value in m, got ", v);
  return v;
}

const Vec3d& checkedAxial(const Vec3d& M) {
  require(M.x == 0 && M.y == 0,
          "cylinder magnet: only axial magnetization (along body z) is "
          "supported, got transverse components Mx = ",
          M.x, " A/m, My = ", M.y, " A/m");
  return M;
}

// Fraction of "inside" used to subtract M from B/mu0: 1 inside, 0 outside,
// 1/2 on a face (the mean of the one-sided limits of the jumping component).
template <typename T>
T insideWeight(T rho, T z, T a, T b) {
  using std::fabs;
  const T radial = rho < a ? T(1) : (rho == a ? T(0.5) : T(0));
  const T axial = fabs(z) < b ? T(1) : (fabs(z) == b ? T(0.5) : T(0));
  return radial * axial;
}

// (H_rho, H_z) in A/m at cylindrical (rho, z) for radius a, half-length b,
// axial magnetization M; minKc floors the complementary modulus at the rims.
template <typename T>
void cylinderAxialField(T rho, T z, T a, T b, T M, T minKc, T& Hrho, T& Hz) {
  using std::fmax;
  using std::sqrt;
  const T chi = insideWeight(rho, z, a, b);
  if (rho == T(0)) {  // exact on-axis formula, no 0/0 in the radial direction
    const T zp = z + b, zm = z - b;
    Hrho = T(0);
    Hz = M / T(2) * (zp / sqrt(zp * zp + a * a) - zm / sqrt(zm * zm + a * a)) - chi * M;
    return;
  }
  T g = (a - rho) / (a + rho);
  if (g * g == T(0)) g = T(0);  // keep cel's p = g^2 and b = g consistent (p = 0 needs b = 0)
  T br = T(0), bz = T(0);
  for (int end = 0; end < 2; ++end) {
    const T zz = end == 0 ? z + b : z - b;
    const T sign = end == 0 ? T(1) : T(-1);
    const T den = sqrt(zz * zz + (a + rho) * (a + rho));
    const T alpha = a / den, beta = zz / den;
    const T kc = fmax(sqrt(zz * zz + (a - rho) * (a - rho)) / den, minKc);
    T radial = T(0), axial = T(0);
    celPair(kc, T(1), T(1), T(-1), g * g, T(1), g, radial, axial);
    br += sign * alpha * radial;
    bz += sign * beta * axial;
  }
  const T pi = T(3.14159265358979323846264338327950288L);
  Hrho = M / pi * br;
  Hz = M / pi * a / (a + rho) * bz - chi * M;
}

}  // namespace

CylinderMagnet::CylinderMagnet(const Pose& pose, double radius, double halfLength,
                               const Vec3d& magnetization, TimeProfile scale)
    : MagnetSource("cylinder magnet", pose, checkedAxial(magnetization), std::move(scale)),
      radius_(checkedPositive(radius, "radius")),
      halfLength_(checkedPositive(halfLength, "half-length")) {}

double CylinderMagnet::volume() const { return 2.0 * kPi * radius_ * radius_ * halfLength_; }

double CylinderMagnet::surfaceDepth(const Vec3d& xBody, Vec3d& outwardNormal) const {
  // The nearer of the side wall and the caps (inside; a negative value outside).
  const double rho = std::hypot(xBody.x, xBody.y);
  const double side = radius_ - rho, cap = halfLength_ - std::fabs(xBody.z);
  if (side < cap) {
    outwardNormal = rho > 0 ? Vec3d{xBody.x / rho, xBody.y / rho, 0} : Vec3d{1, 0, 0};
    return side;
  }
  outwardNormal = {0, 0, xBody.z < 0 ? -1.0 : 1.0};
  return cap;
}

bool CylinderMagnet::containsBody(const Vec3d& xBody) const {
  return std::hypot(xBody.x, xBody.y) <= radius_ && std::fabs(xBody.z) <= halfLength_;
}

Vec3d CylinderMagnet::bodyField(const Vec3d& xBody) const {
  const Vec3d& M = bodyMagnetization();
  const double a = radius_, b = halfLength_;
  if (norm(xBody) > kFarFieldRadii * std::hypot(a, b)) {
    const double V = volume();
    return symmetricMagnetFarField(M, V, {V * a * a / 4.0, V * a * a / 4.0, V * b * b / 3.0},
                                   xBody);
  }
  const double rho = std::hypot(xBody.x, xBody.y);
  // Near a rim, k ~ distance / (2R): floor the distance at kEdgeRegularization max(R, L).
  const double minKc = kEdgeRegularization * std::max(a, b) / (2.0 * a);
  double Hrho = 0, Hz = 0;
  cylinderAxialField(rho, xBody.z, a, b, M.z, minKc, Hrho, Hz);
  if (rho == 0) return {0.0, 0.0, Hz};
  return {Hrho * xBody.x / rho, Hrho * xBody.y / rho, Hz};
}

std::string CylinderMagnet::describe() const {
  return concat("cylinder magnet, radius ", radius_, " m, half-length ", halfLength_, " m, ",
                describeCommon());
}

std::unique_ptr<FieldSource> CylinderMagnet::clone() const {
  return std::make_unique<CylinderMagnet>(*this);
}

}  // namespace sources
}  // namespace lodestone
