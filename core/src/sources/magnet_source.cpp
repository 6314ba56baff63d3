#include "lodestone/core/sources/magnet_source.h"

#include <cmath>
#include <utility>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/sources/point_dipole.h"

namespace lodestone {
inline namespace sources {

void validatePose(const Pose& pose, const char* who) {
  const Vec3d& p = pose.position;
  require(isFinite(p), who, ": pose position must be finite (m), got (", p.x, ", ", p.y, ", ", p.z,
          ")");
  const Mat3d& R = pose.rotation;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      require(std::isfinite(R(i, j)), who, ": pose rotation entry (", i, ", ", j,
              ") must be finite, got ", R(i, j));
  const Mat3d RtR = R.transposed() * R;
  double worst = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      worst = std::fmax(worst, std::fabs(RtR(i, j) - (i == j ? 1.0 : 0.0)));
  require(worst <= 1e-9, who, ": pose rotation is not orthonormal, max |R^T R - I| = ", worst);
  const double det = R(0, 0) * (R(1, 1) * R(2, 2) - R(1, 2) * R(2, 1)) -
                     R(0, 1) * (R(1, 0) * R(2, 2) - R(1, 2) * R(2, 0)) +
                     R(0, 2) * (R(1, 0) * R(2, 1) - R(1, 1) * R(2, 0));
  require(det > 0, who, ": pose rotation must be proper (det = +1), got det = ", det);
}

MagnetSource::MagnetSource(const char* kind, const Pose& pose, const Vec3d& magnetization,
                           TimeProfile scale)
    : kind_(kind), pose_(pose), M_(magnetization), scale_(std::move(scale)) {
  validatePose(pose, kind);
  require(isFinite(magnetization), kind, ": magnetization must be finite (A/m), got (",
          magnetization.x, ", ", magnetization.y, ", ", magnetization.z, ")");
}

void MagnetSource::setPose(const Pose& pose) {
  validatePose(pose, kind_);
  pose_ = pose;
}

bool MagnetSource::appendFieldSignature(double t, std::vector<double>& out) const {
  out.push_back(double(instanceId()));
  for (int a = 0; a < 3; ++a) out.push_back(pose_.position[a]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out.push_back(pose_.rotation.m[r][c]);
  out.push_back(scale_(t));
  return true;
}

Vec3d MagnetSource::field(const Vec3d& x, double t) const {
  return pose_.vectorToWorld(bodyField(pose_.toLocal(x))) * scale_(t);
}

Vec3d MagnetSource::magnetization(const Vec3d& x, double t) const {
  if (!containsBody(pose_.toLocal(x))) return {};
  return pose_.vectorToWorld(M_) * scale_(t);
}

Vec3d MagnetSource::exteriorContinuation(const Vec3d& x, double t) const {
  Vec3d n;
  const double depth = surfaceDepth(pose_.toLocal(x), n);
  if (depth < 0) return {};
  const double weight = depth > 0 ? 1.0 : 0.5;
  return pose_.vectorToWorld((weight * dot(M_, n)) * n) * scale_(t);
}

void MagnetSource::accumulateField(const Vec3d* x, std::size_t count, double t, Vec3d* out) const {
  const double s = scale_(t);
  for (std::size_t n = 0; n < count; ++n)
    out[n] += pose_.vectorToWorld(bodyField(pose_.toLocal(x[n]))) * s;
}

Vec3d MagnetSource::moment(double t) const {
  return pose_.vectorToWorld(M_) * (volume() * scale_(t));
}

std::string MagnetSource::describeCommon() const {
  const Vec3d& p = pose_.position;
  const Mat3d& R = pose_.rotation;
  return concat("M = (", M_.x, ", ", M_.y, ", ", M_.z, ") A/m (body frame), position (", p.x, ", ",
                p.y, ", ", p.z, ") m, rotation [[", R(0, 0), ", ", R(0, 1), ", ", R(0, 2), "], [",
                R(1, 0), ", ", R(1, 1), ", ", R(1, 2), "], [", R(2, 0), ", ", R(2, 1), ", ",
                R(2, 2), "]], scaled by ", scale_.describe());
}

Vec3d symmetricMagnetFarField(const Vec3d& M, double volume, const Vec3d& secondMoments,
                              const Vec3d& x) {
  const double r = norm(x);
  if (!(r > 0)) return {};
  // H = (1/4pi) grad(M . grad N) with the Newtonian potential of the body
  // N(x) = V/r + (1/2) sum_i I_i d_i^2 (1/r) + O(size^4 / r^5). The trace of I
  // drops out because laplace(1/r) = 0, so use the traceless part.
  const Vec3d dip = dipoleField(M * volume, x);
  const double tr = (secondMoments.x + secondMoments.y + secondMoments.z) / 3.0;
  const Vec3d I{secondMoments.x - tr, secondMoments.y - tr, secondMoments.z - tr};
  // With u = x / r, the fourth derivatives of 1/r contracted with I and M give
  // T_k = [105 u_k (M.u) q - 15 (M_k q + 2 (M.u) I_k u_k + 2 u_k s) + 6 I_k M_k] / r^5,
  // q = sum I_i u_i^2, s = sum I_i M_i u_i; H_oct = T / (8 pi).
  const Vec3d u = x / r;
  const double q = I.x * u.x * u.x + I.y * u.y * u.y + I.z * u.z * u.z;
  const double s = I.x * M.x * u.x + I.y * M.y * u.y + I.z * M.z * u.z;
  const double mu = dot(M, u);
  const double inv = 1.0 / r;
  const double inv5 = inv * inv * inv * inv * inv / (8.0 * kPi);
  Vec3d oct;
  for (int k = 0; k < 3; ++k) {
    const double t = 105.0 * u[k] * mu * q -
                     15.0 * (M[k] * q + 2.0 * mu * I[k] * u[k] + 2.0 * u[k] * s) +
                     6.0 * I[k] * M[k];
    oct[k] = t * inv5;
  }
  const Vec3d H = dip + oct;
  return isFinite(H) ? H : Vec3d{};
}

}  // namespace sources
}  // namespace lodestone
