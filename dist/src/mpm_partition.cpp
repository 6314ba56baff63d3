#include "lodestone/dist/mpm_partition.h"

#include <petscdmda.h>
#include <petscdmswarm.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace dist {

namespace {
void check(PetscErrorCode code, const char* what) {
  if (code != 0) throw Error(concat("PETSc: ", what, " failed with error ", int(code)));
}
#define LODESTONE_PETSC(call) check((call), #call)

// One particle in the swarm: x 3, v 3, C 9, F 9, J, mass, V0, n_p, material,
// id (its bits), magnetic force 3.
constexpr PetscInt kRecord = 33;
constexpr const char* kField = "lodestone_particle";

void put(const Vec3d& v, PetscReal* r) {
  for (int a = 0; a < 3; ++a) r[a] = v[a];
}
void put(const Mat3d& m, PetscReal* r) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r[3 * i + j] = m.m[i][j];
}
Vec3d vec(const PetscReal* r) { return {r[0], r[1], r[2]}; }
Mat3d mat(const PetscReal* r) {
  Mat3d m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m.m[i][j] = r[3 * i + j];
  return m;
}

void pack(const MpmParticles& P, std::size_t p, PetscReal* r) {
  put(P.x[p], r);
  put(P.v[p], r + 3);
  put(P.C[p], r + 6);
  put(P.F[p], r + 15);
  r[24] = P.J[p];
  r[25] = P.mass[p];
  r[26] = P.volume0[p];
  r[27] = P.count[p];
  r[28] = double(P.material[p]);
  r[29] = keyAsDouble(P.id[p]);
  put(P.magneticForce[p], r + 30);
}

void unpack(const PetscReal* r, MpmParticles& P) {
  P.x.push_back(vec(r));
  P.v.push_back(vec(r + 3));
  P.C.push_back(mat(r + 6));
  P.F.push_back(mat(r + 15));
  P.J.push_back(r[24]);
  P.mass.push_back(r[25]);
  P.volume0.push_back(r[26]);
  P.count.push_back(r[27]);
  P.material.push_back(std::uint32_t(r[28]));
  P.id.push_back(keyOf(r[29]));
  P.magneticForce.push_back(vec(r + 30));
}
/// Every node of the ghosted local vector becomes the sum over the ranks of
/// their local vectors' values there (global: scratch of the DMDA).
void sumGhosted(DM dm, Vec local, Vec global) {
  LODESTONE_PETSC(VecSet(global, 0.0));
  LODESTONE_PETSC(DMLocalToGlobalBegin(dm, local, ADD_VALUES, global));
  LODESTONE_PETSC(DMLocalToGlobalEnd(dm, local, ADD_VALUES, global));
  LODESTONE_PETSC(DMGlobalToLocalBegin(dm, global, INSERT_VALUES, local));
  LODESTONE_PETSC(DMGlobalToLocalEnd(dm, global, INSERT_VALUES, local));
}
}  // namespace

struct PetscMpmPartition::Impl {
  MPI_Comm comm = MPI_COMM_NULL;
  int rank = 0, size = 1;
  GridSpec grid;
  DM da = nullptr;       // 4 values per node: momentum, mass
  DM scalars = nullptr;  // 1 value per node, the same boxes (the colour field)
  DM swarm = nullptr;
  Vec global = nullptr, local = nullptr, scalarGlobal = nullptr, scalarLocal = nullptr;
  Index3 boxLo, boxHi, windowLo, windowHi, procs;
  std::vector<int> starts[3];  // per axis: first node of each rank column, plus dims at the end
  std::size_t sent = 0;

  // Sends particle p to target(p) for every p with target(p) != rank, through
  // the swarm; the others stay in place and the received ones are appended.
  template <typename Target>
  std::size_t send(MpmParticles& P, const Target& target) {
    P.checkSizes();
    std::vector<std::uint8_t> leaving(P.size(), 0);
    std::vector<PetscInt> to;
    for (std::size_t p = 0; p < P.size(); ++p) {
      const int r = target(p);
      if (r != rank) {
        leaving[p] = 1;
        to.push_back(r);
      }
    }
    const PetscInt n = PetscInt(to.size());
    LODESTONE_PETSC(DMSwarmSetLocalSizes(swarm, n, 0));
    if (n > 0) {
      PetscReal* rec = nullptr;
      PetscInt* dest = nullptr;
      LODESTONE_PETSC(DMSwarmGetField(swarm, kField, nullptr, nullptr, reinterpret_cast<void**>(&rec)));
      LODESTONE_PETSC(DMSwarmGetField(swarm, DMSwarmField_rank, nullptr, nullptr, reinterpret_cast<void**>(&dest)));
      PetscInt q = 0;
      for (std::size_t p = 0; p < P.size(); ++p) {
        if (!leaving[p]) continue;
        pack(P, p, rec + q * kRecord);
        dest[q] = to[std::size_t(q)];
        ++q;
      }
      LODESTONE_PETSC(DMSwarmRestoreField(swarm, DMSwarmField_rank, nullptr, nullptr, reinterpret_cast<void**>(&dest)));
      LODESTONE_PETSC(DMSwarmRestoreField(swarm, kField, nullptr, nullptr, reinterpret_cast<void**>(&rec)));
      P.removeFlagged(leaving);
    }
    LODESTONE_PETSC(DMSwarmMigrate(swarm, PETSC_TRUE));
    PetscInt received = 0;
    LODESTONE_PETSC(DMSwarmGetLocalSize(swarm, &received));
    if (received > 0) {
      PetscReal* rec = nullptr;
      LODESTONE_PETSC(DMSwarmGetField(swarm, kField, nullptr, nullptr, reinterpret_cast<void**>(&rec)));
      P.reserve(P.size() + std::size_t(received));
      for (PetscInt q = 0; q < received; ++q) unpack(rec + q * kRecord, P);
      LODESTONE_PETSC(DMSwarmRestoreField(swarm, kField, nullptr, nullptr, reinterpret_cast<void**>(&rec)));
    }
    // The ids given to new particles stay the same on every rank.
    unsigned long long next = P.nextId, highest = 0;
    MPI_Allreduce(&next, &highest, 1, MPI_UNSIGNED_LONG_LONG, MPI_MAX, comm);
    P.nextId = highest;
    return std::size_t(n);
  }
};

// The window's width beyond the box, in nodes: a particle's stencil reaches
// two nodes beyond its base node, and surface tension's colour Hessian the
// neighbours of those (core/mpm/partition.h).
constexpr PetscInt kWindowWidth = 3;

PetscMpmPartition::PetscMpmPartition(MPI_Comm comm, const GridSpec& grid) : impl_(std::make_unique<Impl>()) {
  grid.validate("MPM partition grid");
  Impl& m = *impl_;
  m.comm = comm;
  m.grid = grid;
  MPI_Comm_rank(comm, &m.rank);
  MPI_Comm_size(comm, &m.size);
  PetscInt pm = PETSC_DECIDE, pn = PETSC_DECIDE, pp = PETSC_DECIDE;
  LODESTONE_PETSC(DMDACreate3d(comm, DM_BOUNDARY_NONE, DM_BOUNDARY_NONE, DM_BOUNDARY_NONE, DMDA_STENCIL_BOX,
                               grid.dims.i, grid.dims.j, grid.dims.k, pm, pn, pp, 4, kWindowWidth, nullptr, nullptr,
                               nullptr, &m.da));
  if (DMSetUp(m.da) != 0)
    throw Error(concat("MPM partition: PETSc cannot split the ", grid.dims.i, " x ", grid.dims.j, " x ", grid.dims.k,
                       " node grid over ", m.size,
                       " ranks (each rank's box needs at least 3 nodes per axis); use "
                       "fewer ranks"));
  PetscInt xs, ys, zs, xm, ym, zm, gxs, gys, gzs, gxm, gym, gzm, M, N, P;
  LODESTONE_PETSC(DMDAGetCorners(m.da, &xs, &ys, &zs, &xm, &ym, &zm));
  LODESTONE_PETSC(DMDAGetGhostCorners(m.da, &gxs, &gys, &gzs, &gxm, &gym, &gzm));
  LODESTONE_PETSC(DMDAGetInfo(m.da, nullptr, nullptr, nullptr, nullptr, &M, &N, &P, nullptr, nullptr, nullptr, nullptr,
                              nullptr, nullptr));
  m.boxLo = {int(xs), int(ys), int(zs)};
  m.boxHi = {int(xs + xm), int(ys + ym), int(zs + zm)};
  m.windowLo = {int(gxs), int(gys), int(gzs)};
  m.windowHi = {int(gxs + gxm), int(gys + gym), int(gzs + gzm)};
  m.procs = {int(M), int(N), int(P)};
  const PetscInt* l[3] = {nullptr, nullptr, nullptr};
  LODESTONE_PETSC(DMDAGetOwnershipRanges(m.da, &l[0], &l[1], &l[2]));
  for (int a = 0; a < 3; ++a) {
    int s = 0;
    for (int c = 0; c < m.procs[a]; ++c) {
      m.starts[a].push_back(s);
      s += int(l[a][c]);
    }
    m.starts[a].push_back(s);
  }
  // The rank order of the DMDA (x fastest), checked against this rank's box.
  const int column[3] = {int(std::upper_bound(m.starts[0].begin(), m.starts[0].end(), xs) - m.starts[0].begin()) - 1,
                         int(std::upper_bound(m.starts[1].begin(), m.starts[1].end(), ys) - m.starts[1].begin()) - 1,
                         int(std::upper_bound(m.starts[2].begin(), m.starts[2].end(), zs) - m.starts[2].begin()) - 1};
  if (column[0] + m.procs.i * (column[1] + m.procs.j * column[2]) != m.rank)
    throw Error(concat("MPM partition: rank ", m.rank, " owns the DMDA box at column (", column[0], ", ", column[1],
                       ", ", column[2], "), which is not the x-fastest rank order"));
  LODESTONE_PETSC(DMCreateGlobalVector(m.da, &m.global));
  LODESTONE_PETSC(DMCreateLocalVector(m.da, &m.local));
  LODESTONE_PETSC(DMDACreate3d(comm, DM_BOUNDARY_NONE, DM_BOUNDARY_NONE, DM_BOUNDARY_NONE, DMDA_STENCIL_BOX,
                               grid.dims.i, grid.dims.j, grid.dims.k, M, N, P, 1, kWindowWidth, l[0], l[1], l[2],
                               &m.scalars));
  LODESTONE_PETSC(DMSetUp(m.scalars));
  LODESTONE_PETSC(DMCreateGlobalVector(m.scalars, &m.scalarGlobal));
  LODESTONE_PETSC(DMCreateLocalVector(m.scalars, &m.scalarLocal));

  LODESTONE_PETSC(DMCreate(comm, &m.swarm));
  LODESTONE_PETSC(DMSetType(m.swarm, DMSWARM));
  LODESTONE_PETSC(DMSetDimension(m.swarm, 3));
  LODESTONE_PETSC(DMSwarmSetType(m.swarm, DMSWARM_BASIC));
  LODESTONE_PETSC(DMSwarmInitializeFieldRegister(m.swarm));
  LODESTONE_PETSC(DMSwarmRegisterPetscDatatypeField(m.swarm, kField, kRecord, PETSC_REAL));
  LODESTONE_PETSC(DMSwarmFinalizeFieldRegister(m.swarm));
  LODESTONE_PETSC(DMSwarmSetLocalSizes(m.swarm, 0, 0));
}

PetscMpmPartition::~PetscMpmPartition() {
  Impl& m = *impl_;
  if (m.swarm) DMDestroy(&m.swarm);
  if (m.scalarLocal) VecDestroy(&m.scalarLocal);
  if (m.scalarGlobal) VecDestroy(&m.scalarGlobal);
  if (m.scalars) DMDestroy(&m.scalars);
  if (m.local) VecDestroy(&m.local);
  if (m.global) VecDestroy(&m.global);
  if (m.da) DMDestroy(&m.da);
}

int PetscMpmPartition::rank() const { return impl_->rank; }
int PetscMpmPartition::ranks() const { return impl_->size; }
Index3 PetscMpmPartition::boxLo() const { return impl_->boxLo; }
Index3 PetscMpmPartition::boxHi() const { return impl_->boxHi; }
Index3 PetscMpmPartition::windowLo() const { return impl_->windowLo; }
Index3 PetscMpmPartition::windowHi() const { return impl_->windowHi; }
Index3 PetscMpmPartition::rankGrid() const { return impl_->procs; }
std::size_t PetscMpmPartition::sent() const { return impl_->sent; }

int PetscMpmPartition::owner(const Vec3d& x) const {
  const Impl& m = *impl_;
  int column[3];
  for (int a = 0; a < 3; ++a) {
    // The stencil base floor(u - 1/2), taken one up within 1e-9 of the next
    // node: the owner's window grid, whose origin differs, may round u - 1/2
    // either way there, and its window reaches two nodes below its box.
    const double t = (x[a] - m.grid.origin[a]) / m.grid.dx - 0.5;
    double base = std::floor(t + 1e-9);
    if (!std::isfinite(base)) base = 0;
    const int b = int(std::clamp(base, 0.0, double(m.grid.dims[a] - 1)));
    column[a] = int(std::upper_bound(m.starts[a].begin(), m.starts[a].end(), b) - m.starts[a].begin()) - 1;
    column[a] = std::clamp(column[a], 0, m.procs[a] - 1);
  }
  return column[0] + m.procs.i * (column[1] + m.procs.j * column[2]);
}

std::size_t PetscMpmPartition::migrate(MpmParticles& particles) {
  const std::size_t n = impl_->send(particles, [&](std::size_t p) { return owner(particles.x[p]); });
  impl_->sent += n;
  return n;
}

void PetscMpmPartition::gatherToRoot(MpmParticles& particles) {
  impl_->send(particles, [](std::size_t) { return 0; });
}

void PetscMpmPartition::sumNodes(MpmNode* window, std::size_t count) {
  Impl& m = *impl_;
  PetscInt length = 0;
  LODESTONE_PETSC(VecGetLocalSize(m.local, &length));
  require(std::size_t(length) == 4 * count, "MPM partition: the window holds ", count,
          " nodes, the DMDA's ghosted box ", length / 4);
  PetscScalar* a = nullptr;
  LODESTONE_PETSC(VecGetArray(m.local, &a));
  for (std::size_t n = 0; n < count; ++n) {
    put(window[n].momentum, a + 4 * n);
    a[4 * n + 3] = window[n].mass;
  }
  LODESTONE_PETSC(VecRestoreArray(m.local, &a));
  sumGhosted(m.da, m.local, m.global);
  const PetscScalar* b = nullptr;
  LODESTONE_PETSC(VecGetArrayRead(m.local, &b));
  for (std::size_t n = 0; n < count; ++n) {
    window[n].momentum = vec(b + 4 * n);
    window[n].mass = b[4 * n + 3];
  }
  LODESTONE_PETSC(VecRestoreArrayRead(m.local, &b));
}

void PetscMpmPartition::sumScalars(double* window, std::size_t count) {
  Impl& m = *impl_;
  PetscInt length = 0;
  LODESTONE_PETSC(VecGetLocalSize(m.scalarLocal, &length));
  require(std::size_t(length) == count, "MPM partition: the window holds ", count,
          " values, the DMDA's ghosted box ", length);
  PetscScalar* a = nullptr;
  LODESTONE_PETSC(VecGetArray(m.scalarLocal, &a));
  std::copy(window, window + count, a);
  LODESTONE_PETSC(VecRestoreArray(m.scalarLocal, &a));
  sumGhosted(m.scalars, m.scalarLocal, m.scalarGlobal);
  const PetscScalar* b = nullptr;
  LODESTONE_PETSC(VecGetArrayRead(m.scalarLocal, &b));
  std::copy(b, b + length, window);
  LODESTONE_PETSC(VecRestoreArrayRead(m.scalarLocal, &b));
}

double PetscMpmPartition::maxOverRanks(double value) {
  double out = value;
  MPI_Allreduce(&value, &out, 1, MPI_DOUBLE, MPI_MAX, impl_->comm);
  return out;
}

void PetscMpmPartition::sumOverRanks(double* values, int n) {
  MPI_Allreduce(MPI_IN_PLACE, values, n, MPI_DOUBLE, MPI_SUM, impl_->comm);
}

std::vector<double> PetscMpmPartition::allGather(const std::vector<double>& local) {
  const Impl& m = *impl_;
  const int mine = int(local.size());
  std::vector<int> counts(std::size_t(m.size)), offsets(std::size_t(m.size), 0);
  MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, m.comm);
  for (int r = 1; r < m.size; ++r) offsets[std::size_t(r)] = offsets[std::size_t(r - 1)] + counts[std::size_t(r - 1)];
  std::vector<double> all(std::size_t(offsets.back() + counts.back()));
  MPI_Allgatherv(local.data(), mine, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE, m.comm);
  return all;
}

std::string PetscMpmPartition::describe() const {
  const Impl& m = *impl_;
  return concat(m.size, " ranks as ", m.procs.i, " x ", m.procs.j, " x ", m.procs.k, " boxes of the ", m.grid.dims.i,
                " x ", m.grid.dims.j, " x ", m.grid.dims.k, " node grid; rank ", m.rank, " owns nodes [", m.boxLo.i,
                ", ", m.boxHi.i, ") x [", m.boxLo.j, ", ", m.boxHi.j, ") x [", m.boxLo.k, ", ", m.boxHi.k,
                ") and holds [", m.windowLo.i, ", ", m.windowHi.i, ") x [", m.windowLo.j, ", ", m.windowHi.j, ") x [",
                m.windowLo.k, ", ", m.windowHi.k, ")");
}

}  // namespace dist
}  // namespace lodestone
