#pragma once
// The material element matrix of one trilinear cell from the responses at
// its 8 Gauss points:
//   E = (dx / 8) sum_q dN_q^T (iso_q I + rank1_q h_q h_q^T) dN_q
//     = (dx / 8) sum_q [iso_q (dN_q . dN_q) + rank1_q (dN_q h_q)(dN_q h_q)^T],
// written as the packed upper triangle (row by row, 36 values).
//
// On x86-64 CPUs with AVX2 and FMA (checked at run time) the rows are
// accumulated as 4-wide vectors over the full 8x8 and packed at the end;
// elsewhere the packed triangle is accumulated point by point. The two agree
// to round-off (tests/core/test_langevin_batch.cpp).
#include "lodestone/core/field/langevin_batch.h"

namespace lodestone {
inline namespace field {

/// E (36 values) for a cell of spacing dx (m) from its Gauss-point
/// responses (iso, rank1 and h of `r`); fastest path on this CPU.
void buildElementMatrix(double dx, const ResponseBatch& r, double E[36]);
/// The point-by-point path.
void buildElementMatrixScalar(double dx, const ResponseBatch& r, double E[36]);
/// The vector path; returns false (and writes nothing) when this CPU or
/// build has none.
bool buildElementMatrixVector(double dx, const ResponseBatch& r, double E[36]);

}  // namespace field
}  // namespace lodestone
