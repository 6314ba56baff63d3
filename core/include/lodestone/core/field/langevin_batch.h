#pragma once
// The Langevin response (M, dM/dH as iso I + rank1 h h^T, and W) at the 8
// Gauss points of a cell at once: what every evaluation of the field solve
// computes 8 times per material cell.
//
// On x86-64 CPUs with AVX2 and FMA (checked at run time; the build itself
// stays portable) the 8 points run as two 4-wide vectors, with glibc's vector
// exp, log and log1p (libmvec, within 4 ulp) in place of the scalar ones,
// about twice as fast; elsewhere, and for other laws, respond() point by
// point. Both follow the same branches as langevinTriple() (series below
// a = 1, exponential forms above) and agree to a few ulp
// (tests/core/test_langevin_batch.cpp), so results are deterministic on a
// given machine but not bitwise equal between the two paths.
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace field {

/// Responses at 8 points, as arrays (one entry per point).
struct ResponseBatch {
  double Mx[8], My[8], Mz[8];  ///< magnetization, A/m
  double iso[8], rank1[8];     ///< dM/dH = iso I + rank1 h h^T (dimensionless)
  double hx[8], hy[8], hz[8];  ///< unit field direction (0 where H = 0)
  double W[8];                 ///< co-energy density, A^2/m^2
};

/// Fills `out` with respond(law, n[q], H[q]) for q = 0..7, on the fastest
/// path this CPU has (see the header comment).
void respondBatch(const MagnetizationLaw<double>& law, const double n[8], const Vec3d H[8], ResponseBatch& out);

/// The point-by-point path (respond() at each point), for any law.
void respondBatchScalar(const MagnetizationLaw<double>& law, const double n[8], const Vec3d H[8],
                        ResponseBatch& out);

/// The vector path for the Langevin law; returns false (and writes nothing)
/// when this CPU or build has none.
bool respondBatchVector(const MagnetizationLaw<double>& law, const double n[8], const Vec3d H[8],
                        ResponseBatch& out);

}  // namespace field
}  // namespace lodestone
