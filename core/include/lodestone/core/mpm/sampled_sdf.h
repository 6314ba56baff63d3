#pragma once
// A signed-distance function sampled on a dense node grid: the shape of a
// level-set or mesh collider and emitter, in its body frame.
//
// Values phi_ijk (m, negative inside) sit on the nodes of a GridSpec
// (node (i,j,k) at origin + h (i,j,k), x fastest), stored as float. Between
// nodes phi is the trilinear interpolant, and the normal is the normalised
// gradient of that interpolant (piecewise bilinear, continuous within a cell).
// Outside the sampled box, phi is the value at the nearest point of the box
// plus the distance to it, so phi grows away from the box and stays positive
// when the box's boundary is outside the shape (as it is for a level set
// padded by its narrow band).
//
// Narrow-band level sets (OpenVDB's) hold exact distances only within a few
// voxels of the surface and +-background further away; that is all a
// collider (sign and normal near the surface) and an emitter (sign) need.
//
// Immutable after construction; share it through std::shared_ptr<const
// SampledSdf> (colliders and emitter shapes copy the pointer, not the grid).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace mpm {

/// The inside fraction 1 - H_eps(phi) of a sample at signed distance phi
/// (m) with the smoothed Heaviside of width eps (m) (Osher and Fedkiw 2003,
/// eq. 1.23): 1 for phi <= -eps, 0 for phi >= eps.
inline double smoothedInsideFraction(double phi, double eps) {
  if (phi <= -eps) return 1;
  if (phi >= eps) return 0;
  return 0.5 - phi / (2 * eps) - std::sin(kPi * phi / eps) / (2 * kPi);
}

class SampledSdf {
 public:
  SampledSdf() = default;
  /// `values`: one per node of `spec` (x fastest), m, negative inside.
  /// `description` names the source (file and grid) in messages. Throws
  /// InvalidArgument when the spec is invalid, the size does not match, a
  /// value is not finite, or no node is inside (phi <= 0).
  SampledSdf(const GridSpec& spec, std::vector<float> values, std::string description = {});

  const GridSpec& spec() const { return spec_; }
  const std::vector<float>& values() const { return values_; }
  const std::string& description() const { return description_; }

  /// Signed distance (m) at body-frame point xb (m), negative inside.
  double signedDistance(const Vec3d& xb) const;
  /// Gradient of the trilinear interpolant at xb (dimensionless; about unit
  /// length near the surface). Outside the box: that of the nearest box point.
  Vec3d gradient(const Vec3d& xb) const;
  /// Outward unit normal at xb: the normalised gradient, +z where it vanishes.
  Vec3d normal(const Vec3d& xb) const;

  /// Volume of the inside {phi < 0}, m^3: the node sum of a smoothed
  /// Heaviside of width 1.5 h (Osher and Fedkiw 2003, eq. 1.23), second-order
  /// accurate for smooth surfaces resolved by the grid.
  double volume() const;
  /// Body-frame box (m) of the nodes with phi <= 0, grown by one spacing h
  /// (clamped to the sampled box): the region an emitter has to scan.
  void interiorBounds(Vec3d& lo, Vec3d& hi) const;

  /// The shallowest ridge of the inside, m: the smallest depth -phi of a
  /// node that lies no higher than its two neighbours along an axis while
  /// the surfaces on either side face opposite ways (the unit normals at the
  /// two neighbours meet at more than 120 degrees): the medial surface of the
  /// solid's thinnest wall, to within h/2. A point that enters the solid by less than this is still nearest
  /// the face it came through. Convex edges and corners are not ridges; a
  /// solid without one (a narrow band's flat interior) gives its deepest
  /// value, at most the band's half width.
  double insideRidgeDepth() const { return insideRidge_; }
  /// The same for the outside (phi > 0), m; infinite when the outside has no
  /// ridge (phi grows past the sampled box).
  double outsideRidgeDepth() const { return outsideRidge_; }

 private:
  /// Clamps xb into the box; returns the cell (i,j,k) and the fractions.
  void locate(const Vec3d& xb, int& i, int& j, int& k, double& fx, double& fy, double& fz) const;
  void findRidges();  // sets insideRidge_, outsideRidge_
  double at(int i, int j, int k) const { return double(values_[spec_.index(i, j, k)]); }

  GridSpec spec_;
  std::vector<float> values_;
  std::string description_;
  Vec3d hi_;          // body-frame position of the last node, m
  double invDx_ = 0;  // 1 / h, 1/m
  Vec3d interiorLo_, interiorHi_;
  double insideRidge_ = 0, outsideRidge_ = 0;  // m
};

inline void SampledSdf::locate(const Vec3d& xb, int& i, int& j, int& k, double& fx, double& fy, double& fz) const {
  const double gx = (std::min(std::max(xb.x, spec_.origin.x), hi_.x) - spec_.origin.x) * invDx_;
  const double gy = (std::min(std::max(xb.y, spec_.origin.y), hi_.y) - spec_.origin.y) * invDx_;
  const double gz = (std::min(std::max(xb.z, spec_.origin.z), hi_.z) - spec_.origin.z) * invDx_;
  i = std::min(int(gx), spec_.dims.i - 2);
  j = std::min(int(gy), spec_.dims.j - 2);
  k = std::min(int(gz), spec_.dims.k - 2);
  fx = gx - i;
  fy = gy - j;
  fz = gz - k;
}

inline double SampledSdf::signedDistance(const Vec3d& xb) const {
  int i, j, k;
  double fx, fy, fz;
  locate(xb, i, j, k, fx, fy, fz);
  const std::size_t si = 1, sj = std::size_t(spec_.dims.i), sk = sj * std::size_t(spec_.dims.j);
  const float* p = values_.data() + spec_.index(i, j, k);
  const double c00 = p[0] + fx * (p[si] - p[0]);
  const double c10 = p[sj] + fx * (p[sj + si] - p[sj]);
  const double c01 = p[sk] + fx * (p[sk + si] - p[sk]);
  const double c11 = p[sk + sj] + fx * (p[sk + sj + si] - p[sk + sj]);
  const double c0 = c00 + fy * (c10 - c00), c1 = c01 + fy * (c11 - c01);
  double outside = 0;  // distance from xb to the sampled box
  if (xb.x < spec_.origin.x || xb.x > hi_.x || xb.y < spec_.origin.y || xb.y > hi_.y || xb.z < spec_.origin.z ||
      xb.z > hi_.z) {
    const double dx = std::max({spec_.origin.x - xb.x, 0.0, xb.x - hi_.x});
    const double dy = std::max({spec_.origin.y - xb.y, 0.0, xb.y - hi_.y});
    const double dz = std::max({spec_.origin.z - xb.z, 0.0, xb.z - hi_.z});
    outside = std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  return c0 + fz * (c1 - c0) + outside;
}

inline Vec3d SampledSdf::gradient(const Vec3d& xb) const {
  int i, j, k;
  double fx, fy, fz;
  locate(xb, i, j, k, fx, fy, fz);
  const double v000 = at(i, j, k), v100 = at(i + 1, j, k), v010 = at(i, j + 1, k), v110 = at(i + 1, j + 1, k);
  const double v001 = at(i, j, k + 1), v101 = at(i + 1, j, k + 1), v011 = at(i, j + 1, k + 1),
               v111 = at(i + 1, j + 1, k + 1);
  const double gx =
      (1 - fz) * ((1 - fy) * (v100 - v000) + fy * (v110 - v010)) + fz * ((1 - fy) * (v101 - v001) + fy * (v111 - v011));
  const double gy =
      (1 - fz) * ((1 - fx) * (v010 - v000) + fx * (v110 - v100)) + fz * ((1 - fx) * (v011 - v001) + fx * (v111 - v101));
  const double gz =
      (1 - fy) * ((1 - fx) * (v001 - v000) + fx * (v101 - v100)) + fy * ((1 - fx) * (v011 - v010) + fx * (v111 - v110));
  return Vec3d{gx, gy, gz} * invDx_;
}

inline Vec3d SampledSdf::normal(const Vec3d& xb) const {
  const Vec3d g = gradient(xb);
  const double n = norm(g);
  return n > 0 ? g / n : Vec3d{0, 0, 1};
}

}  // namespace mpm
}  // namespace lodestone
