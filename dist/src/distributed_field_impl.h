#pragma once
// The distributed field solve's state (DistributedFieldSolve::Impl), shared by
// its set-up and solve (distributed_field_solve.cpp) and its nonlinear
// operator, the residual and Jacobian PETSc's SNES calls
// (distributed_field_operator.cpp).
#include <cstdint>
#include <vector>

#include <petscdmda.h>
#include <petscsnes.h>

#include "lodestone/core/field/langevin_batch.h"
#include "lodestone/dist/distributed_field_solve.h"

namespace lodestone {
inline namespace dist {

/// Moments per multipole block: dipole (3) + quadrupole (9).
constexpr int kMoments = 12;

struct DistributedFieldSolve::Impl {
  MPI_Comm comm;
  GridSpec grid;
  MagnetizationLaw<double> law;
  BoundaryKind boundary;
  DistributedSolveSettings settings;
  int rank = 0, size = 1;
  DM da = nullptr;
  SNES snes = nullptr;
  Mat J = nullptr;
  Vec X = nullptr, R = nullptr, W = nullptr, Xloc = nullptr, Wloc = nullptr, Floc = nullptr;
  PetscInt xs = 0, ys = 0, zs = 0, xm = 0, ym = 0, zm = 0;       // owned nodes
  PetscInt gxs = 0, gys = 0, gzs = 0, gxm = 0, gym = 0, gzm = 0; // ghosted nodes
  double K[8][8];  // vacuum element matrix, m

  // Owned cells (base node owned, below the last node on each axis), in
  // (k, j, i) order; the material slot of each, or -1.
  Index3 cellLo, cellHi;
  std::vector<int> cellSlot;
  // Material cells owned by this rank.
  std::vector<Index3> matBase;
  std::vector<double> nq;         // 8 per cell, 1/m^3
  std::vector<Vec3d> hext;        // 8 per cell, A/m
  std::vector<std::uint32_t> matBlock;  // block of each material cell
  std::vector<Vec3d> fromCentre;  // cell origin minus block centre, m
  std::vector<double> Mq;         // 24 per cell: M at the Gauss points of the last residual, A/m
  // Blocks (same on every rank) and the open wall.
  std::vector<Vec3d> blockCentre;
  int clearance = 1 << 30;
  std::vector<Index3> fixedNodes;  // owned fixed nodes
  std::vector<double> fixedTarget; // their target values g, A
  double fixedScale = 1;           // c of the fixed rows, m
  bool haveMaterial = false;
  double setupSeconds = 0;

  ~Impl() {
    if (snes) SNESDestroy(&snes);
    if (J) MatDestroy(&J);
    for (Vec* v : {&X, &R, &W, &Xloc, &Wloc, &Floc})
      if (*v) VecDestroy(v);
    if (da) DMDestroy(&da);
  }

  bool ownsCellBase(int i, int j, int k) const {
    return i >= cellLo.i && i < cellHi.i && j >= cellLo.j && j < cellHi.j && k >= cellLo.k && k < cellHi.k;
  }
  PetscInt localIndex(int i, int j, int k) const {
    return (PetscInt(i) - gxs) + gxm * ((PetscInt(j) - gys) + gym * (PetscInt(k) - gzs));
  }

  template <typename Fn>
  void forOwnedCells(const Fn& fn) const {
    std::size_t n = 0;
    for (int k = cellLo.k; k < cellHi.k; ++k)
      for (int j = cellLo.j; j < cellHi.j; ++j)
        for (int i = cellLo.i; i < cellHi.i; ++i) fn(i, j, k, cellSlot[n++]);
  }

  void respondCell(const PetscScalar* const* const* x, std::size_t s, ResponseBatch& rb) const;
  void evaluateMaterial(const PetscScalar* const* const* x, std::vector<double>& moments);
  void setWallTargets(const std::vector<double>& moments);
  PetscErrorCode residual(Vec Xg, Vec F);
  PetscErrorCode jacobian(Vec Xg, Mat P);
};

}  // namespace dist
}  // namespace lodestone
