#include "lodestone/core/sources/cuboid_magnet.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace sources {

namespace {

Vec3d checkedHalfSize(const Vec3d& h) {
  const char* axis[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k)
    require(std::isfinite(h[k]) && h[k] > 0, "cuboid magnet: half-size along ", axis[k],
            " must be a positive finite value in m, got ", h[k]);
  return h;
}

// ln((v2 + R2) / (v1 + R1)) with Ri = sqrt(rho2 + vi^2), v1 <= v2, rho2 > 0:
// the integral of dV / R over [v1, v2]. Written so that no argument cancels:
// with both ends on one side the ratio is 1 + (an exactly computed small
// quantity), and across zero ln(v + R) for v < 0 uses (v + R)(R - v) = rho2.
template <typename T>
T logRatio(T v1, T v2, T rho2) {
  using std::log;
  using std::log1p;
  using std::sqrt;
  const T r1 = sqrt(rho2 + v1 * v1);
  const T r2 = sqrt(rho2 + v2 * v2);
  const T dv = v2 - v1;
  if (v1 >= T(0)) return log1p(dv * (T(1) + (v1 + v2) / (r1 + r2)) / (v1 + r1));
  if (v2 <= T(0)) return log1p(dv * (T(1) - (v1 + v2) / (r1 + r2)) / (r2 - v2));
  return log((v2 + r2) * (r1 - v1) / rho2);
}

// 4 pi / sigma times the H field of the rectangle |u| <= hu, |v| <= hv in the
// plane w = 0 carrying unit charge density, at (pu, pv, pw). Components
// (u, v, w). minRho2 floors the squared distance to the edge lines.
template <typename T>
void rectangleField(T pu, T pv, T w, T hu, T hv, T minRho2, T out[3]) {
  using std::atan;
  using std::fmax;
  using std::sqrt;
  const T U[2] = {pu - hu, pu + hu};  // pu - x' at x' = +hu, -hu
  const T V[2] = {pv - hv, pv + hv};
  const T w2 = w * w;
  // Integral of U / R^3 over U then V: -[ln(V + R)] summed over corners.
  const T lv1 = logRatio(V[0], V[1], fmax(U[1] * U[1] + w2, minRho2));
  const T lv0 = logRatio(V[0], V[1], fmax(U[0] * U[0] + w2, minRho2));
  out[0] = lv0 - lv1;
  const T lu1 = logRatio(U[0], U[1], fmax(V[1] * V[1] + w2, minRho2));
  const T lu0 = logRatio(U[0], U[1], fmax(V[0] * V[0] + w2, minRho2));
  out[1] = lu0 - lu1;
  // Integral of w / R^3: [atan(U V / (w R))]. In the plane (w == 0) this is
  // zero outside the rectangle and the mean of +-2 pi inside: zero.
  T hw = T(0);
  if (w != T(0)) {
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        const T uv = U[a] * V[b];
        if (uv == T(0)) continue;
        const T R = sqrt(U[a] * U[a] + V[b] * V[b] + w2);
        const T term = atan(uv / (w * R));
        hw += (a == b) ? term : -term;
      }
  }
  out[2] = hw;
}

// H (A/m) of the cuboid with half-sizes h and magnetization M at body point x.
template <typename T>
void cuboidField(const T x[3], const T h[3], const T M[3], T minRho2, T H[3]) {
  H[0] = H[1] = H[2] = T(0);
  for (int k = 0; k < 3; ++k) {
    if (M[k] == T(0)) continue;
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      const T sigma = side == 0 ? M[k] : -M[k];  // M . n on x_k = +h_k, -h_k
      const T c = side == 0 ? h[k] : -h[k];
      T f[3];
      rectangleField(x[i], x[j], x[k] - c, h[i], h[j], minRho2, f);
      const T s = sigma / T(4 * 3.14159265358979323846264338327950288L);
      H[i] += s * f[0];
      H[j] += s * f[1];
      H[k] += s * f[2];
    }
  }
}

}  // namespace

CuboidMagnet::CuboidMagnet(const Pose& pose, const Vec3d& halfSize, const Vec3d& magnetization,
                           TimeProfile scale)
    : MagnetSource("cuboid magnet", pose, magnetization, std::move(scale)),
      half_(checkedHalfSize(halfSize)) {}

double CuboidMagnet::volume() const { return 8.0 * half_.x * half_.y * half_.z; }

bool CuboidMagnet::containsBody(const Vec3d& xBody) const {
  return std::fabs(xBody.x) <= half_.x && std::fabs(xBody.y) <= half_.y &&
         std::fabs(xBody.z) <= half_.z;
}

double CuboidMagnet::surfaceDepth(const Vec3d& xBody, Vec3d& outwardNormal) const {
  // Inside: the nearest face. Outside: a negative value (the distance is not needed).
  int axis = 0;
  double depth = half_.x - std::fabs(xBody.x);
  for (int a = 1; a < 3; ++a) {
    const double d = half_[a] - std::fabs(xBody[a]);
    if (d < depth) depth = d, axis = a;
  }
  outwardNormal = Vec3d{};
  outwardNormal[axis] = xBody[axis] < 0 ? -1.0 : 1.0;
  return depth;
}

Vec3d CuboidMagnet::bodyField(const Vec3d& xBody) const {
  const Vec3d& M = bodyMagnetization();
  const double r = norm(xBody);
  if (r > kFarFieldRadii * norm(half_)) {
    const double V = volume();
    const Vec3d I{V * half_.x * half_.x / 3.0, V * half_.y * half_.y / 3.0,
                  V * half_.z * half_.z / 3.0};
    return symmetricMagnetFarField(M, V, I, xBody);
  }
  const double hmax = std::max({half_.x, half_.y, half_.z});
  const double floor = kEdgeRegularization * hmax;
  const double x[3] = {xBody.x, xBody.y, xBody.z};
  const double h[3] = {half_.x, half_.y, half_.z};
  const double m[3] = {M.x, M.y, M.z};
  double H[3];
  cuboidField(x, h, m, floor * floor, H);
  return {H[0], H[1], H[2]};
}

std::string CuboidMagnet::describe() const {
  return concat("cuboid magnet, half-sizes (", half_.x, ", ", half_.y, ", ", half_.z, ") m, ",
                describeCommon());
}

std::unique_ptr<FieldSource> CuboidMagnet::clone() const {
  return std::make_unique<CuboidMagnet>(*this);
}

}  // namespace sources
}  // namespace lodestone
