#pragma once
// Material points of the reference MLS-MPM as a structure of arrays. Every
// array has size() entries; index p is one material point. Solids carry the
// deformation gradient F, fluids only the volume ratio J (F stays I for them);
// both carry the APIC affine matrix C (the MLS velocity gradient, 1/s).
// Magnetic points carry n_p micro-particles (dimensionless), zero otherwise.
//
// The solver reorders points by grid cell every MpmSettings::reorderInterval
// substeps (default 20; 0 keeps the order) and after the first substep that
// follows an emission, and removes
// points that leave the domain under OutOfDomainPolicy::Remove or become
// non-finite; `id` is a persistent identity that survives both.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "lodestone/core/base/mat3.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace mpm {

struct MpmParticles {
  std::vector<Vec3d> x;                 ///< position, m
  std::vector<Vec3d> v;                 ///< velocity, m/s
  std::vector<Mat3d> C;                 ///< APIC affine matrix = velocity gradient, 1/s
  std::vector<Mat3d> F;                 ///< deformation gradient (solids; I for fluids)
  std::vector<double> J;                ///< volume ratio det F (fluids track it directly)
  std::vector<double> mass;             ///< kg
  std::vector<double> volume0;          ///< reference (rest) volume V_p^0, m^3
  std::vector<double> count;            ///< n_p, micro-particles carried (0 for non-magnetic)
  std::vector<std::uint32_t> material;  ///< index into the solver's material list
  std::vector<std::uint64_t> id;        ///< persistent identity
  std::vector<Vec3d> magneticForce;     ///< magnetic force of the last field solve, N (per-particle coupling only)
  std::uint64_t nextId = 0;             ///< id given to the next added point

  std::size_t size() const { return x.size(); }
  bool empty() const { return x.empty(); }
  void reserve(std::size_t n);
  void clear();
  /// Releases the arrays' unused capacity.
  void shrinkToFit();

  /// Appends one point at rest state (F = I, J = 1, C = 0, no magnetic force)
  /// and returns its index. Values are validated: finite position (m) and
  /// velocity (m/s), mass (kg) and volume0 (m^3) positive and finite, count
  /// finite and >= 0.
  std::size_t add(const Vec3d& position, const Vec3d& velocity, double mass, double volume0, double count,
                  std::uint32_t material);

  /// Throws InvalidArgument unless every array has size() entries.
  void checkSizes() const;

  /// Removes the points with remove[p] != 0 (remove has size() entries),
  /// keeping the order of the others. Returns how many were removed.
  std::size_t removeFlagged(const std::vector<std::uint8_t>& remove);

  /// Reorders the points: new point p is old point order[p]; `order` must be
  /// a permutation of 0..size()-1.
  void permute(const std::vector<std::uint32_t>& order);

  /// Total mass, kg.
  double totalMass() const;
  /// Total linear momentum sum m_p v_p, kg*m/s.
  Vec3d linearMomentum() const;
  /// Total APIC angular momentum about the origin (kg*m^2/s) for quadratic
  /// B-splines on a grid of spacing dx (m):
  ///   L = sum_p x_p x m_p v_p + m_p (dx^2/4) eps : C_p^T,
  /// the second term being the spin of the affine velocity field (Jiang et
  /// al. 2015; D_p = dx^2/4 I for quadratic B-splines).
  Vec3d angularMomentum(double dx) const;
  /// Centre of mass, m (zero when there are no points).
  Vec3d centreOfMass() const;
};

}  // namespace mpm
}  // namespace lodestone
