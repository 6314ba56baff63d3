// The distributed field solve's nonlinear operator: the material's response,
// the open wall's targets, and the residual and Jacobian SNES evaluates.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>

#include "distributed_field_impl.h"
#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/field/element_build.h"
#include "lodestone/core/field/langevin_batch.h"
#include "lodestone/core/field/multipole_blocks.h"
#include "lodestone/core/field/open_wall_lattice.h"
#include "lodestone/core/field/open_wall_sum.h"
#include "lodestone/core/field/q1_element.h"

#if !defined(PETSC_SUCCESS)  // PETSc before 3.19
#define PETSC_SUCCESS 0
#endif

namespace lodestone {
inline namespace dist {

// The law's response at the Gauss points of material cell s for the ghosted
// potential x: H = H_ext - grad phi.
void DistributedFieldSolve::Impl::respondCell(const PetscScalar* const* const* x, std::size_t s,
                                              ResponseBatch& rb) const {
  const Index3 b = matBase[s];
  const double h = grid.dx;
  double pc[8];
  for (int c = 0; c < 8; ++c) pc[c] = x[b.k + ((c >> 2) & 1)][b.j + ((c >> 1) & 1)][b.i + (c & 1)];
  double gradient[8][3];
  q1::gaussGradients(pc, gradient);
  Vec3d Hq[8];
  for (int q = 0; q < 8; ++q) {
    const Vec3d& he = hext[s * 8 + std::size_t(q)];
    Hq[q] = {he.x - gradient[q][0] / h, he.y - gradient[q][1] / h, he.z - gradient[q][2] / h};
  }
  respondBatch(law, &nq[s * 8], Hq, rb);
}

// M at every material Gauss point for the ghosted potential x, kept in Mq,
// and the block moments of this rank's cells (moments[b * 12 ...]).
void DistributedFieldSolve::Impl::evaluateMaterial(const PetscScalar* const* const* x, std::vector<double>& moments) {
  const double h = grid.dx, w = grid.cellVolume() / 8.0;
  moments.assign(blockCentre.size() * kMoments, 0.0);
  Mq.resize(matBase.size() * 24);
  for (std::size_t s = 0; s < matBase.size(); ++s) {
    ResponseBatch rb;
    respondCell(x, s, rb);
    Vec3d dipole, upper[3];
    for (int q = 0; q < 8; ++q) {
      const Vec3d M{rb.Mx[q], rb.My[q], rb.Mz[q]};
      Mq[s * 24 + std::size_t(q) * 3 + 0] = M.x;
      Mq[s * 24 + std::size_t(q) * 3 + 1] = M.y;
      Mq[s * 24 + std::size_t(q) * 3 + 2] = M.z;
      dipole += w * M;
      for (int a = 0; a < 3; ++a)
        if ((q >> a) & 1) upper[a] += w * M;
    }
    if (boundary == BoundaryKind::Open) {
      const Multipole mp = cellMultipole(dipole, upper, fromCentre[s], h);
      double* m = &moments[std::size_t(matBlock[s]) * kMoments];
      for (int a = 0; a < 3; ++a) m[a] += mp.dipole[a];
      for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c) m[3 + 3 * a + c] += mp.quadrupole[a][c];
    }
  }
}

// The target values of this rank's fixed nodes: the far field of the summed
// block moments on the open wall (core's lattice and interpolation), 0 at
// the pinned node of the shield.
void DistributedFieldSolve::Impl::setWallTargets(const std::vector<double>& moments) {
  fixedTarget.assign(fixedNodes.size(), 0.0);
  if (boundary != BoundaryKind::Open || fixedNodes.empty()) return;
  std::vector<Multipole> blocks(blockCentre.size());
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    blocks[b].centre = blockCentre[b];
    const double* m = &moments[b * kMoments];
    blocks[b].dipole = {m[0], m[1], m[2]};
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) blocks[b].quadrupole[a][c] = m[3 + 3 * a + c];
  }
  const OpenWallLattice lattice(grid, clearance);
  // The lattice nodes this rank's fixed nodes interpolate from, summed once.
  std::map<std::size_t, Index3> needed;
  for (const Index3& n : fixedNodes)
    lattice.interpolate(n.i, n.j, n.k, [&](int p, int q, int r) {
      needed.emplace(grid.index(p, q, r), Index3{p, q, r});
      return 0.0;
    });
  std::vector<Index3> only;
  only.reserve(needed.size());
  for (const auto& entry : needed) only.push_back(entry.second);
  const OpenWallSum farField(blocks, grid, multipoleBlockEdgeFor(clearance), clearance, lattice, &only);
  for (std::size_t f = 0; f < fixedNodes.size(); ++f) {
    const Index3 n = fixedNodes[f];
    fixedTarget[f] =
        lattice.interpolate(n.i, n.j, n.k, [&](int p, int q, int r) { return farField.sum(p, q, r) / (4.0 * kPi); });
  }
}

// F = K phi_g - G^T w M(phi) on the rows of free nodes, where phi_g is phi
// with the fixed nodes at their targets g; c (phi - g) on the fixed rows.
PetscErrorCode DistributedFieldSolve::Impl::residual(Vec Xg, Vec F) {
  PetscFunctionBeginUser;
  PetscCall(DMGlobalToLocalBegin(da, Xg, INSERT_VALUES, Xloc));
  PetscCall(DMGlobalToLocalEnd(da, Xg, INSERT_VALUES, Xloc));
  std::vector<double> moments;
  {
    const PetscScalar*** x = nullptr;
    PetscCall(DMDAVecGetArrayRead(da, Xloc, (void*)&x));
    evaluateMaterial(x, moments);
    PetscCall(DMDAVecRestoreArrayRead(da, Xloc, (void*)&x));
  }
  if (boundary == BoundaryKind::Open && !moments.empty())
    MPI_Allreduce(MPI_IN_PLACE, moments.data(), int(moments.size()), MPI_DOUBLE, MPI_SUM, comm);
  setWallTargets(moments);
  // phi_g: the potential with the fixed nodes at their targets.
  PetscCall(VecCopy(Xg, W));
  {
    PetscScalar*** wv = nullptr;
    PetscCall(DMDAVecGetArray(da, W, &wv));
    for (std::size_t f = 0; f < fixedNodes.size(); ++f)
      wv[fixedNodes[f].k][fixedNodes[f].j][fixedNodes[f].i] = fixedTarget[f];
    PetscCall(DMDAVecRestoreArray(da, W, &wv));
  }
  PetscCall(DMGlobalToLocalBegin(da, W, INSERT_VALUES, Wloc));
  PetscCall(DMGlobalToLocalEnd(da, W, INSERT_VALUES, Wloc));
  PetscCall(VecZeroEntries(Floc));
  {
    const PetscScalar*** wl = nullptr;
    PetscScalar*** fl = nullptr;
    PetscCall(DMDAVecGetArrayRead(da, Wloc, (void*)&wl));
    PetscCall(DMDAVecGetArray(da, Floc, &fl));
    const double h = grid.dx, scale = h * h / 8.0;
    forOwnedCells([&](int i, int j, int k, int slot) {
      double pc[8];
      for (int c = 0; c < 8; ++c) pc[c] = wl[k + ((c >> 2) & 1)][j + ((c >> 1) & 1)][i + (c & 1)];
      // (dx^2 / 8) sum_q dN_qc . (grad phi_q - M_q), grad phi in reference units / dx.
      double f[8][3];
      q1::gaussGradients(pc, f);
      for (int q = 0; q < 8; ++q)
        for (int a = 0; a < 3; ++a)
          f[q][a] = f[q][a] / h - (slot >= 0 ? Mq[std::size_t(slot) * 24 + std::size_t(q) * 3 + std::size_t(a)] : 0.0);
      double res[8];
      q1::gaussDivergenceTranspose(f, res);
      for (int c = 0; c < 8; ++c) fl[k + ((c >> 2) & 1)][j + ((c >> 1) & 1)][i + (c & 1)] += scale * res[c];
    });
    PetscCall(DMDAVecRestoreArray(da, Floc, &fl));
    PetscCall(DMDAVecRestoreArrayRead(da, Wloc, (void*)&wl));
  }
  PetscCall(VecZeroEntries(F));
  PetscCall(DMLocalToGlobalBegin(da, Floc, ADD_VALUES, F));
  PetscCall(DMLocalToGlobalEnd(da, Floc, ADD_VALUES, F));
  {
    const PetscScalar*** xv = nullptr;
    PetscScalar*** fv = nullptr;
    PetscCall(DMDAVecGetArrayRead(da, Xg, (void*)&xv));
    PetscCall(DMDAVecGetArray(da, F, &fv));
    for (std::size_t f = 0; f < fixedNodes.size(); ++f) {
      const Index3 n = fixedNodes[f];
      fv[n.k][n.j][n.i] = fixedScale * (xv[n.k][n.j][n.i] - fixedTarget[f]);
    }
    PetscCall(DMDAVecRestoreArray(da, F, &fv));
    PetscCall(DMDAVecRestoreArrayRead(da, Xg, (void*)&xv));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

// J = K + sum_cells (material element matrices) on the free rows and
// columns, c I on the fixed ones (the wall's dependence on M is left out:
// the wall follows M through the residual, one Newton iteration late).
PetscErrorCode DistributedFieldSolve::Impl::jacobian(Vec Xg, Mat P) {
  PetscFunctionBeginUser;
  PetscCall(DMGlobalToLocalBegin(da, Xg, INSERT_VALUES, Xloc));
  PetscCall(DMGlobalToLocalEnd(da, Xg, INSERT_VALUES, Xloc));
  PetscCall(MatZeroEntries(P));
  const PetscScalar*** x = nullptr;
  PetscCall(DMDAVecGetArrayRead(da, Xloc, (void*)&x));
  const double h = grid.dx;
  const auto fixed = [&](int i, int j, int k) {
    if (boundary == BoundaryKind::Shield) return i == 0 && j == 0 && k == 0;
    return grid.isBoundaryNode(i, j, k);
  };
  PetscErrorCode status = PETSC_SUCCESS;
  forOwnedCells([&](int i, int j, int k, int slot) {
    if (status != PETSC_SUCCESS) return;
    double E[8][8];
    for (int c = 0; c < 8; ++c)
      for (int d = 0; d < 8; ++d) E[c][d] = K[c][d];
    if (slot >= 0) {
      ResponseBatch rb;
      respondCell(x, std::size_t(slot), rb);
      double packed[36];
      buildElementMatrix(h, rb, packed);
      for (int r = 0, m = 0; r < 8; ++r)
        for (int c = r; c < 8; ++c, ++m) {
          E[r][c] += packed[m];
          if (c != r) E[c][r] += packed[m];
        }
    }
    PetscInt idx[8];
    for (int c = 0; c < 8; ++c) {
      const int ci = i + (c & 1), cj = j + ((c >> 1) & 1), ck = k + ((c >> 2) & 1);
      idx[c] = fixed(ci, cj, ck) ? -1 : localIndex(ci, cj, ck);  // negative: left out
    }
    status = MatSetValuesLocal(P, 8, idx, 8, idx, &E[0][0], ADD_VALUES);
  });
  PetscCall(status);
  PetscCall(DMDAVecRestoreArrayRead(da, Xloc, (void*)&x));
  for (const Index3& n : fixedNodes) {
    const PetscInt row = localIndex(n.i, n.j, n.k);
    PetscCall(MatSetValuesLocal(P, 1, &row, 1, &row, &fixedScale, ADD_VALUES));
  }
  PetscCall(MatAssemblyBegin(P, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(P, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(PETSC_SUCCESS);
}

}  // namespace dist
}  // namespace lodestone
