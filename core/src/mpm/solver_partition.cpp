// The MPM solver shared by several processes (MpmSolver::setPartition,
// mpm/partition.h): the split, particle ownership, and the magnetic points
// gathered from every process for the field solve and its decisions.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/mpm/solver.h"

namespace lodestone {
inline namespace mpm {

void MpmSolver::setPartition(std::shared_ptr<MpmPartition> partition) {
  require(partition != nullptr, "MPM solver: setPartition needs a partition, got null");
  const GridSpec& g = settings_.grid;
  const Index3 lo = partition->windowLo(), hi = partition->windowHi();
  for (int a = 0; a < 3; ++a)
    require(lo[a] >= 0 && hi[a] <= g.dims[a] && hi[a] - lo[a] >= 3, "MPM solver: partition window [", lo.i, ", ",
            lo.j, ", ", lo.k, ") .. (", hi.i, ", ", hi.j, ", ", hi.k, ") of rank ", partition->rank(),
            " must lie in the grid of ", g.dims.i, " x ", g.dims.j, " x ", g.dims.k,
            " nodes and hold at least 3 nodes per axis");
  partition_ = std::move(partition);
  GridSpec window;
  window.dx = g.dx;
  window.origin = g.nodePosition(lo.i, lo.j, lo.k);
  window.dims = {hi.i - lo.i, hi.j - lo.j, hi.k - lo.k};
  grid_ = MpmGrid(window);
  grid_.setWholeLayout(true);  // the processes add whole arrays (sumNodes)
  grid_.setColourSum([p = partition_.get()](double* colour, std::size_t count) { p->sumScalars(colour, count); });
  std::size_t removed = 0, nonFinite = 0;
  enforceDomain(removed, nonFinite);  // every process the same: owners are decided inside the domain
  keepOwnedParticles(0);
  particles_.shrinkToFit();  // particles emitted before the split were made on every process
  particlesDirty_ = false;
  knownMaxSpeed_ = -1.0;  // of the particles before the split
}

void MpmSolver::keepOwnedParticles(std::size_t from) {
  if (!partition_ || from >= particles_.size()) return;
  const int me = partition_->rank();
  std::vector<std::uint8_t> drop(particles_.size(), 0);
  for (std::size_t p = from; p < particles_.size(); ++p) drop[p] = partition_->owner(particles_.x[p]) != me;
  particles_.removeFlagged(drop);
}

std::size_t MpmSolver::totalParticles() const {
  if (!partition_) return particles_.size();
  double n = double(particles_.size());
  partition_->sumOverRanks(&n, 1);
  return std::size_t(n);
}

void MpmSolver::gatherParticlesToRoot() {
  if (partition_) partition_->gatherToRoot(particles_);
}

void MpmSolver::magneticPoints(MagneticPoints& pts) const {
  pts.index.clear();
  pts.x.clear();
  pts.count.clear();
  pts.id.clear();
  if (!partition_) {
    // (clear() keeps the storage: the arrays grow only past their largest count.)
    for (std::size_t p = 0; p < particles_.size(); ++p) {
      if (!isMagneticPoint(p)) continue;
      pts.index.push_back(std::uint32_t(p));
      pts.x.push_back(particles_.x[p]);
      pts.count.push_back(particles_.count[p]);
    }
    return;
  }
  // Records of 7 values: id, x, y, z, n_p, rank, index.
  constexpr std::size_t R = 7;
  const int me = partition_->rank();
  std::vector<double> local;
  for (std::size_t p = 0; p < particles_.size(); ++p) {
    if (!isMagneticPoint(p)) continue;
    local.insert(local.end(), {keyAsDouble(particles_.id[p]), particles_.x[p].x, particles_.x[p].y, particles_.x[p].z,
                               particles_.count[p], double(me), double(p)});
  }
  const std::vector<double> all = allGatherByKey(*partition_, local, R);
  for (std::size_t q = 0; q < all.size() / R; ++q) {
    const double* r = &all[q * R];
    pts.id.push_back(keyOf(r[0]));
    pts.x.push_back({r[1], r[2], r[3]});
    pts.count.push_back(r[4]);
    pts.index.push_back(int(r[5]) == me ? std::uint32_t(r[6]) : MagneticPoints::kElsewhere);
  }
}

bool MpmSolver::magneticPointsWithin(double distance) const {
  const auto magnetic = [this](std::size_t p) { return isMagneticPoint(p); };
  if (!partition_) return reuse_.pointsWithin(particles_.x, magnetic, distance);
  const std::vector<Vec3d>& then = reuse_.positions();
  bool within = !reuse_.samples().empty() && then.size() == solvedIds_.size();
  const double d2 = distance * distance;
  double count = 0;  // this process's magnetic points
  for (std::size_t p = 0; p < particles_.size(); ++p) {
    if (!magnetic(p)) continue;
    ++count;
    if (!within) continue;
    const auto it = std::lower_bound(solvedIds_.begin(), solvedIds_.end(), particles_.id[p]);
    within = it != solvedIds_.end() && *it == particles_.id[p] &&
             norm2(particles_.x[p] - then[std::size_t(it - solvedIds_.begin())]) <= d2;
  }
  double agreed[2] = {within ? 0.0 : 1.0, count};
  partition_->sumOverRanks(agreed, 2);
  return agreed[0] == 0 && agreed[1] == double(then.size());
}

}  // namespace mpm
}  // namespace lodestone
