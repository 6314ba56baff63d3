#include "lodestone/dist/distributed_field_solve.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <sstream>

#include <petscdmda.h>
#include <petscsnes.h>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/stopwatch.h"
#include "lodestone/core/field/element_build.h"
#include "lodestone/core/field/langevin_batch.h"
#include "lodestone/core/field/multipole_blocks.h"
#include "lodestone/core/field/open_wall_lattice.h"
#include "lodestone/core/field/q1_element.h"
#include "lodestone/core/field/wall_clearance.h"
#include "distributed_field_impl.h"

#if !defined(PETSC_SUCCESS)  // PETSc before 3.19
#define PETSC_SUCCESS 0
#endif

namespace lodestone {
inline namespace dist {

namespace {
constexpr q1::Tables kQ1 = q1::makeTables();

void check(PetscErrorCode code, const char* what) {
  if (code != 0) throw Error(concat("PETSc: ", what, " failed with error ", int(code)));
}
#define LODESTONE_PETSC(call) check((call), #call)

/// Throws the same InvalidArgument on every rank when any rank has a
/// message (the lowest such rank's). Collective.
void throwIfAnyRank(MPI_Comm comm, const std::string& message) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  int mine = message.empty() ? size : rank, first = size;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm);
  if (first == size) return;
  int length = int(message.size());
  MPI_Bcast(&length, 1, MPI_INT, first, comm);
  std::string text = rank == first ? message : std::string(std::size_t(length), ' ');
  MPI_Bcast(text.data(), length, MPI_CHAR, first, comm);
  throw InvalidArgument(text);
}

/// The vacuum element matrix dx (1/8) sum_q dN_q . dN_q (the Q1 Laplacian
/// stiffness of one cell; q1_stencil.h assembles the same matrix).
void vacuumElement(double h, double K[8][8]) {
  for (int c = 0; c < 8; ++c)
    for (int d = 0; d < 8; ++d) {
      double s[6];
      q1::gradientProducts(kQ1, c, d, s);
      K[c][d] = h * (s[0] + s[1] + s[2]);
    }
}

/// Levels of PCMG on a DMDA of `dims` nodes: halve the cells while every
/// axis has an even cell count and keeps at least 4 cells.
int multigridLevels(const Index3& dims) {
  int levels = 1;
  Index3 c{dims.i - 1, dims.j - 1, dims.k - 1};
  while (c.i % 2 == 0 && c.j % 2 == 0 && c.k % 2 == 0 && c.i / 2 >= 4 && c.j / 2 >= 4 && c.k / 2 >= 4) {
    c = {c.i / 2, c.j / 2, c.k / 2};
    ++levels;
  }
  return levels;
}
}  // namespace

const char* toString(DistributedPreconditioner kind) {
  switch (kind) {
    case DistributedPreconditioner::GeometricMultigrid:
      return "mg";
    case DistributedPreconditioner::Gamg:
      return "gamg";
    case DistributedPreconditioner::Hypre:
      return "hypre";
  }
  return "?";
}

DistributedPreconditioner parseDistributedPreconditioner(const std::string& name) {
  if (name == "mg") return DistributedPreconditioner::GeometricMultigrid;
  if (name == "gamg") return DistributedPreconditioner::Gamg;
  if (name == "hypre") return DistributedPreconditioner::Hypre;
  throw InvalidArgument(concat("distributed preconditioner '", name, "': expected mg, gamg or hypre"));
}

void DistributedSolveSettings::validate() const {
  require(std::isfinite(tolerance) && tolerance > 0 && tolerance < 1,
          "distributed field solve: tolerance must be in (0, 1), got ", tolerance);
  require(maxNewtonIterations >= 1, "distributed field solve: maxNewtonIterations must be >= 1, got ",
          maxNewtonIterations);
}

std::string DistributedSolveReport::summary() const {
  std::ostringstream os;
  if (trivial)
    os << "field solve on " << ranks << " ranks: nothing magnetized, H = H_ext";
  else
    os << "field solve on " << ranks << " ranks: " << (converged ? "converged" : "NOT converged") << " ("
       << reason << ") in " << newtonIterations << " Newton iterations, " << linearIterations
       << " CG iterations, relative residual " << relativeResidual << ", " << seconds << " s";
  return os.str();
}

namespace {
PetscErrorCode formFunction(SNES, Vec X, Vec F, void* ctx) {
  try {
    return static_cast<DistributedFieldSolve::Impl*>(ctx)->residual(X, F);
  } catch (const std::exception& e) {
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "%s", e.what());
  }
}
PetscErrorCode formJacobian(SNES, Vec X, Mat Jm, Mat P, void* ctx) {
  try {
    PetscCall(static_cast<DistributedFieldSolve::Impl*>(ctx)->jacobian(X, P));
    if (Jm != P) {
      PetscCall(MatAssemblyBegin(Jm, MAT_FINAL_ASSEMBLY));
      PetscCall(MatAssemblyEnd(Jm, MAT_FINAL_ASSEMBLY));
    }
    return PETSC_SUCCESS;
  } catch (const std::exception& e) {
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "%s", e.what());
  }
}
}  // namespace

DistributedFieldSolve::DistributedFieldSolve(MPI_Comm comm, const GridSpec& grid, const MagnetizationLaw<double>& law,
                                             BoundaryKind boundary, const DistributedSolveSettings& settings)
    : impl_(std::make_unique<Impl>()) {
  grid.validate("distributed field-solve grid");
  settings.validate();
  require(boundary != BoundaryKind::Open || (grid.dims.i >= 3 && grid.dims.j >= 3 && grid.dims.k >= 3),
          "distributed field-solve grid: the open boundary needs at least 3 nodes per axis, got ", grid.dims.i,
          " x ", grid.dims.j, " x ", grid.dims.k);
  Impl& m = *impl_;
  m.comm = comm;
  m.grid = grid;
  m.law = law;
  m.boundary = boundary;
  m.settings = settings;
  MPI_Comm_rank(comm, &m.rank);
  MPI_Comm_size(comm, &m.size);
  m.fixedScale = grid.dx;
  vacuumElement(grid.dx, m.K);
  LODESTONE_PETSC(DMDACreate3d(comm, DM_BOUNDARY_NONE, DM_BOUNDARY_NONE, DM_BOUNDARY_NONE, DMDA_STENCIL_BOX,
                               grid.dims.i, grid.dims.j, grid.dims.k, PETSC_DECIDE, PETSC_DECIDE, PETSC_DECIDE, 1, 1,
                               nullptr, nullptr, nullptr, &m.da));
  LODESTONE_PETSC(DMSetFromOptions(m.da));
  LODESTONE_PETSC(DMSetUp(m.da));
  LODESTONE_PETSC(DMDASetUniformCoordinates(m.da, grid.origin.x, grid.maxCorner().x, grid.origin.y,
                                            grid.maxCorner().y, grid.origin.z, grid.maxCorner().z));
  LODESTONE_PETSC(DMDAGetCorners(m.da, &m.xs, &m.ys, &m.zs, &m.xm, &m.ym, &m.zm));
  LODESTONE_PETSC(DMDAGetGhostCorners(m.da, &m.gxs, &m.gys, &m.gzs, &m.gxm, &m.gym, &m.gzm));
  m.cellLo = {int(m.xs), int(m.ys), int(m.zs)};
  m.cellHi = {int(std::min<PetscInt>(m.xs + m.xm, grid.dims.i - 1)),
              int(std::min<PetscInt>(m.ys + m.ym, grid.dims.j - 1)),
              int(std::min<PetscInt>(m.zs + m.zm, grid.dims.k - 1))};
  LODESTONE_PETSC(DMCreateGlobalVector(m.da, &m.X));
  LODESTONE_PETSC(VecDuplicate(m.X, &m.R));
  LODESTONE_PETSC(VecDuplicate(m.X, &m.W));
  LODESTONE_PETSC(DMCreateLocalVector(m.da, &m.Xloc));
  LODESTONE_PETSC(VecDuplicate(m.Xloc, &m.Wloc));
  LODESTONE_PETSC(VecDuplicate(m.Xloc, &m.Floc));
  LODESTONE_PETSC(DMCreateMatrix(m.da, &m.J));
  LODESTONE_PETSC(MatSetOption(m.J, MAT_SYMMETRIC, PETSC_TRUE));
  LODESTONE_PETSC(MatSetOption(m.J, MAT_SPD, PETSC_TRUE));
  LODESTONE_PETSC(MatSetOption(m.J, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));

  // Fixed nodes owned here.
  for (PetscInt k = m.zs; k < m.zs + m.zm; ++k)
    for (PetscInt j = m.ys; j < m.ys + m.ym; ++j)
      for (PetscInt i = m.xs; i < m.xs + m.xm; ++i) {
        const bool fixed = boundary == BoundaryKind::Shield ? (i == 0 && j == 0 && k == 0)
                                                            : grid.isBoundaryNode(int(i), int(j), int(k));
        if (fixed) m.fixedNodes.push_back({int(i), int(j), int(k)});
      }

  LODESTONE_PETSC(SNESCreate(comm, &m.snes));
  LODESTONE_PETSC(SNESSetDM(m.snes, m.da));
  LODESTONE_PETSC(SNESSetFunction(m.snes, m.R, formFunction, &m));
  LODESTONE_PETSC(SNESSetJacobian(m.snes, m.J, m.J, formJacobian, &m));
  LODESTONE_PETSC(SNESSetType(m.snes, SNESNEWTONLS));
  SNESLineSearch ls;
  LODESTONE_PETSC(SNESGetLineSearch(m.snes, &ls));
  LODESTONE_PETSC(SNESLineSearchSetType(ls, SNESLINESEARCHBT));
  LODESTONE_PETSC(SNESSetTolerances(m.snes, 0.0, settings.tolerance, 0.0, settings.maxNewtonIterations, 1000000));
  LODESTONE_PETSC(SNESKSPSetUseEW(m.snes, PETSC_TRUE));
  KSP ksp;
  PC pc;
  LODESTONE_PETSC(SNESGetKSP(m.snes, &ksp));
  LODESTONE_PETSC(KSPSetType(ksp, KSPCG));
  LODESTONE_PETSC(KSPGetPC(ksp, &pc));
  // PCMG coarsens the DMDA by halving the cells of every axis: a grid whose
  // cell counts do not halve at least twice gets PCGAMG instead (describe()
  // says which runs).
  DistributedPreconditioner kind = settings.preconditioner;
  if (kind == DistributedPreconditioner::GeometricMultigrid && multigridLevels(grid.dims) < 3)
    kind = DistributedPreconditioner::Gamg;
  switch (kind) {
    case DistributedPreconditioner::GeometricMultigrid:
      LODESTONE_PETSC(PCSetType(pc, PCMG));
      LODESTONE_PETSC(PCMGSetLevels(pc, multigridLevels(grid.dims), nullptr));
      LODESTONE_PETSC(PCMGSetGalerkin(pc, PC_MG_GALERKIN_BOTH));
      break;
    case DistributedPreconditioner::Gamg:
      LODESTONE_PETSC(PCSetType(pc, PCGAMG));
      break;
    case DistributedPreconditioner::Hypre: {
#if defined(PETSC_HAVE_HYPRE)
      LODESTONE_PETSC(PCSetType(pc, PCHYPRE));
      LODESTONE_PETSC(PCHYPRESetType(pc, "boomeramg"));
#else
      throw InvalidArgument("distributed preconditioner 'hypre': this PETSc was built without hypre");
#endif
      break;
    }
  }
  LODESTONE_PETSC(SNESSetFromOptions(m.snes));
}

DistributedFieldSolve::~DistributedFieldSolve() = default;

void DistributedFieldSolve::setMaterial(GridView<const double> n, const AppliedFieldFunction& appliedField) {
  Impl& m = *impl_;
  const auto t0 = SteadyClock::now();
  require(n.spec == m.grid, "distributed field solve: the density grid does not match the solver grid");
  require(bool(appliedField), "distributed field solve: no applied-field function given");
  // Densities at the corners of this rank's cells.
  std::string bad;
  for (int k = m.cellLo.k; k <= m.cellHi.k && k < m.grid.dims.k && bad.empty(); ++k)
    for (int j = m.cellLo.j; j <= m.cellHi.j && j < m.grid.dims.j && bad.empty(); ++j)
      for (int i = m.cellLo.i; i <= m.cellHi.i && i < m.grid.dims.i && bad.empty(); ++i)
        if (!(std::isfinite(n(i, j, k)) && n(i, j, k) >= 0))
          bad = concat("distributed field solve: micro-particle density n at node (", i, ", ", j, ", ", k, ") is ",
                       n(i, j, k), " 1/m^3; it must be finite and >= 0");
  throwIfAnyRank(m.comm, bad);

  m.cellSlot.clear();
  m.matBase.clear();
  for (int k = m.cellLo.k; k < m.cellHi.k; ++k)
    for (int j = m.cellLo.j; j < m.cellHi.j; ++j)
      for (int i = m.cellLo.i; i < m.cellHi.i; ++i) {
        bool any = false;
        for (int c = 0; c < 8 && !any; ++c) any = n(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)) > 0;
        m.cellSlot.push_back(any ? int(m.matBase.size()) : -1);
        if (any) m.matBase.push_back({i, j, k});
      }
  const std::size_t cells = m.matBase.size();
  const double h = m.grid.dx;
  m.nq.assign(cells * 8, 0.0);
  m.hext.assign(cells * 8, Vec3d{});
  std::vector<Vec3d> x(cells * 8);
  for (std::size_t s = 0; s < cells; ++s) {
    const Index3 b = m.matBase[s];
    double nc[8];
    for (int c = 0; c < 8; ++c) nc[c] = n(b.i + (c & 1), b.j + ((c >> 1) & 1), b.k + ((c >> 2) & 1));
    const Vec3d o = m.grid.nodePosition(b.i, b.j, b.k);
    for (int q = 0; q < 8; ++q) {
      m.nq[s * 8 + std::size_t(q)] = q1::interpolate(kQ1, q, nc);
      x[s * 8 + std::size_t(q)] =
          o + h * Vec3d{q1::gaussAbscissa(q & 1), q1::gaussAbscissa((q >> 1) & 1), q1::gaussAbscissa((q >> 2) & 1)};
    }
  }
  if (cells > 0) appliedField(x.data(), x.size(), m.hext.data());
  std::string nonFinite;
  for (std::size_t g = 0; g < cells * 8 && nonFinite.empty(); ++g)
    if (!isFinite(m.hext[g]))
      nonFinite = concat("distributed field solve: the applied field is not finite at (", x[g].x, ", ", x[g].y,
                         ", ", x[g].z, ") m");
  throwIfAnyRank(m.comm, nonFinite);

  unsigned long long total = cells;
  MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, m.comm);
  m.haveMaterial = total > 0;

  // The material's clearance to the wall, and the multipole blocks: the
  // same edge, tiling and n-weighted centres as core's problem
  // (multipole_blocks.h), from sums reduced over the ranks.
  std::vector<std::size_t> flat(cells);
  for (std::size_t s = 0; s < cells; ++s) flat[s] = m.grid.index(m.matBase[s].i, m.matBase[s].j, m.matBase[s].k);
  int clearance = materialWallClearance(m.grid, flat.data(), cells);
  MPI_Allreduce(&clearance, &m.clearance, 1, MPI_INT, MPI_MIN, m.comm);
  m.blockCentre.clear();
  m.matBlock.assign(cells, 0);
  m.fromCentre.assign(cells, Vec3d{});
  if (m.boundary == BoundaryKind::Open && m.haveMaterial) {
    const MultipoleBlockTiling tiling(m.grid.cellDims(), multipoleBlockEdgeFor(m.clearance));
    // Per block: n-weighted sum of cell centres, n sum, plain sum of centres, cell count.
    struct Record {
      double key, count, wx, wy, wz, weight, gx, gy, gz;
    };
    std::map<std::uint64_t, Record> local;
    std::vector<std::uint64_t> keys(cells);
    for (std::size_t s = 0; s < cells; ++s) {
      const Index3 b = m.matBase[s];
      keys[s] = tiling.key(b.i, b.j, b.k);
      const Vec3d o = m.grid.nodePosition(b.i, b.j, b.k) + Vec3d{0.5 * h, 0.5 * h, 0.5 * h};
      double nc = 0;
      for (int q = 0; q < 8; ++q) nc += m.nq[s * 8 + std::size_t(q)];
      Record& r = local.try_emplace(keys[s], Record{double(keys[s]), 0, 0, 0, 0, 0, 0, 0, 0}).first->second;
      r.count += 1;
      r.wx += nc * o.x;
      r.wy += nc * o.y;
      r.wz += nc * o.z;
      r.weight += nc;
      r.gx += o.x;
      r.gy += o.y;
      r.gz += o.z;
    }
    std::vector<Record> mine;
    for (const auto& kv : local) mine.push_back(kv.second);
    constexpr int kFields = int(sizeof(Record) / sizeof(double));
    int sendCount = int(mine.size()) * kFields;
    std::vector<int> counts(std::size_t(m.size)), displs(std::size_t(m.size));
    MPI_Allgather(&sendCount, 1, MPI_INT, counts.data(), 1, MPI_INT, m.comm);
    int totalCount = 0;
    for (int r = 0; r < m.size; ++r) {
      displs[std::size_t(r)] = totalCount;
      totalCount += counts[std::size_t(r)];
    }
    std::vector<Record> all(std::size_t(totalCount / kFields));
    MPI_Allgatherv(mine.data(), sendCount, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, m.comm);
    std::map<std::uint64_t, Record> merged;  // in key order: the same block numbering on every rank
    for (const Record& r : all) {
      const auto key = std::uint64_t(r.key);
      auto [it, fresh] = merged.try_emplace(key, r);
      if (!fresh) {
        Record& t = it->second;
        t.count += r.count;
        t.wx += r.wx;
        t.wy += r.wy;
        t.wz += r.wz;
        t.weight += r.weight;
        t.gx += r.gx;
        t.gy += r.gy;
        t.gz += r.gz;
      }
    }
    std::map<std::uint64_t, std::uint32_t> number;
    for (const auto& kv : merged) {
      const Record& r = kv.second;
      number[kv.first] = std::uint32_t(m.blockCentre.size());
      m.blockCentre.push_back(r.weight > 0 ? Vec3d{r.wx, r.wy, r.wz} / r.weight
                                           : Vec3d{r.gx, r.gy, r.gz} / r.count);
    }
    for (std::size_t s = 0; s < cells; ++s) {
      m.matBlock[s] = number[keys[s]];
      m.fromCentre[s] = m.grid.nodePosition(m.matBase[s].i, m.matBase[s].j, m.matBase[s].k) -
                        m.blockCentre[m.matBlock[s]];
    }
  }
  double seconds = secondsSince(t0);
  MPI_Allreduce(MPI_IN_PLACE, &seconds, 1, MPI_DOUBLE, MPI_MAX, m.comm);
  m.setupSeconds = seconds;
}

DistributedSolveReport DistributedFieldSolve::solve() {
  Impl& m = *impl_;
  const auto t0 = SteadyClock::now();
  DistributedSolveReport rep;
  rep.ranks = m.size;
  rep.setupSeconds = m.setupSeconds;
  LODESTONE_PETSC(VecZeroEntries(m.X));
  LODESTONE_PETSC(formFunction(m.snes, m.X, m.R, &m));
  PetscReal f0 = 0;
  LODESTONE_PETSC(VecNorm(m.R, NORM_2, &f0));
  if (!m.haveMaterial || !(f0 > 0)) {
    rep.trivial = rep.converged = true;
    rep.reason = "nothing magnetized";
    rep.seconds = secondsSince(t0);
    return rep;
  }
  LODESTONE_PETSC(SNESSolve(m.snes, nullptr, m.X));
  SNESConvergedReason reason;
  LODESTONE_PETSC(SNESGetConvergedReason(m.snes, &reason));
  PetscInt newton = 0, linear = 0;
  LODESTONE_PETSC(SNESGetIterationNumber(m.snes, &newton));
  LODESTONE_PETSC(SNESGetLinearSolveIterations(m.snes, &linear));
  Vec F = nullptr;
  PetscReal fn = 0;
  LODESTONE_PETSC(SNESGetFunction(m.snes, &F, nullptr, nullptr));
  LODESTONE_PETSC(VecNorm(F, NORM_2, &fn));
  if (m.boundary == BoundaryKind::Shield) {
    // Mean 0, as core's shield potential (a constant does not change H).
    PetscScalar sum = 0;
    LODESTONE_PETSC(VecSum(m.X, &sum));
    LODESTONE_PETSC(VecShift(m.X, -sum / PetscScalar(m.grid.nodeCount())));
  }
  rep.converged = reason > 0;
  rep.reason = SNESConvergedReasons[reason];
  rep.newtonIterations = int(newton);
  rep.linearIterations = int(linear);
  rep.relativeResidual = double(fn / f0);
  rep.seconds = secondsSince(t0);
  MPI_Allreduce(MPI_IN_PLACE, &rep.seconds, 1, MPI_DOUBLE, MPI_MAX, m.comm);
  return rep;
}

std::vector<double> DistributedFieldSolve::gatherPotential(int root) const {
  const Impl& m = *impl_;
  Vec natural = nullptr, all = nullptr;
  VecScatter toRoot = nullptr;
  LODESTONE_PETSC(DMDACreateNaturalVector(m.da, &natural));
  LODESTONE_PETSC(DMDAGlobalToNaturalBegin(m.da, m.X, INSERT_VALUES, natural));
  LODESTONE_PETSC(DMDAGlobalToNaturalEnd(m.da, m.X, INSERT_VALUES, natural));
  // VecScatterCreateToZero gathers on rank 0; another root gets it sent on.
  LODESTONE_PETSC(VecScatterCreateToZero(natural, &toRoot, &all));
  LODESTONE_PETSC(VecScatterBegin(toRoot, natural, all, INSERT_VALUES, SCATTER_FORWARD));
  LODESTONE_PETSC(VecScatterEnd(toRoot, natural, all, INSERT_VALUES, SCATTER_FORWARD));
  std::vector<double> out;
  if (m.rank == 0) {
    const PetscScalar* a = nullptr;
    LODESTONE_PETSC(VecGetArrayRead(all, &a));
    out.assign(a, a + m.grid.nodeCount());
    LODESTONE_PETSC(VecRestoreArrayRead(all, &a));
  }
  if (root != 0) {
    if (m.rank == 0) MPI_Send(out.data(), int(out.size()), MPI_DOUBLE, root, 0, m.comm);
    if (m.rank == root) {
      out.resize(m.grid.nodeCount());
      MPI_Recv(out.data(), int(out.size()), MPI_DOUBLE, 0, 0, m.comm, MPI_STATUS_IGNORE);
    }
    if (m.rank == 0) out.clear();
  }
  VecScatterDestroy(&toRoot);
  VecDestroy(&all);
  VecDestroy(&natural);
  return out;
}

Index3 DistributedFieldSolve::ownedLo() const { return {int(impl_->xs), int(impl_->ys), int(impl_->zs)}; }
Index3 DistributedFieldSolve::ownedHi() const {
  return {int(impl_->xs + impl_->xm), int(impl_->ys + impl_->ym), int(impl_->zs + impl_->zm)};
}
int DistributedFieldSolve::ranks() const { return impl_->size; }
int DistributedFieldSolve::rank() const { return impl_->rank; }

std::string DistributedFieldSolve::describe() const {
  const Impl& m = *impl_;
  KSP ksp;
  PC pc;
  KSPType kspType;
  PCType pcType;
  SNESType snesType;
  SNESLineSearch ls;
  SNESLineSearchType lsType;
  LODESTONE_PETSC(SNESGetType(m.snes, &snesType));
  LODESTONE_PETSC(SNESGetLineSearch(m.snes, &ls));
  LODESTONE_PETSC(SNESLineSearchGetType(ls, &lsType));
  LODESTONE_PETSC(SNESGetKSP(m.snes, &ksp));
  LODESTONE_PETSC(KSPGetType(ksp, &kspType));
  LODESTONE_PETSC(KSPGetPC(ksp, &pc));
  LODESTONE_PETSC(PCGetType(pc, &pcType));
  PetscInt px = 0, py = 0, pz = 0;
  LODESTONE_PETSC(DMDAGetInfo(m.da, nullptr, nullptr, nullptr, nullptr, &px, &py, &pz, nullptr, nullptr, nullptr,
                              nullptr, nullptr, nullptr));
  std::ostringstream os;
  os << "DMDA " << m.grid.dims.i << "x" << m.grid.dims.j << "x" << m.grid.dims.k << " nodes on " << px << "x" << py
     << "x" << pz << " ranks, SNES " << snesType << " (line search " << lsType << "), KSP " << kspType << ", PC "
     << pcType;
  if (std::string(pcType) == PCMG) {
    PetscInt levels = 0;
    LODESTONE_PETSC(PCMGGetLevels(pc, &levels));
    os << " (" << levels << " levels, Galerkin)";
  }
  os << ", " << toString(m.boundary) << " wall";
  return os.str();
}

}  // namespace dist
}  // namespace lodestone
