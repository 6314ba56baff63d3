#include "lodestone/core/mpm/particles.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <type_traits>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/kept_capacity.h"
#include "lodestone/core/base/parallel.h"

namespace lodestone {
inline namespace mpm {

namespace {
constexpr std::size_t kPermuteGrain = 8192;

/// Whether every element of `a` has the bytes of a[0]: any permutation
/// leaves such an array as it is (in many scenes the micro-particle counts,
/// the magnetic forces, the materials, even the masses and volumes).
template <typename V>
bool allBytesEqual(const std::vector<V>& a) {
  if (a.size() < 2) return true;
  std::atomic<bool> differs{false};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(1, a.size(), kPermuteGrain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      if (differs.load(std::memory_order_relaxed)) return;
                      for (std::size_t p = r.begin(); p != r.end(); ++p)
                        if (std::memcmp(&a[p], &a[0], sizeof(V)) != 0) {
                          differs.store(true, std::memory_order_relaxed);
                          return;
                        }
                    });
  return !differs.load();
}

/// a[p] <- a[order[p]] through `scratch` (room for a.size() elements of the
/// widest attribute): gathered into it, then copied back, so that `a` keeps
/// its storage. A new array per attribute would cost a zeroing pass and the
/// first touch of its pages each time, three times the gather's own time.
/// An array of equal elements is left alone: one read instead of four passes.
template <typename V>
void permuteArray(std::vector<V>& a, const std::vector<std::uint32_t>& order, unsigned char* scratch) {
  static_assert(std::is_trivially_copyable<V>::value, "particle attributes are copied as bytes");
  if (allBytesEqual(a)) return;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), kPermuteGrain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t p = r.begin(); p != r.end(); ++p)
                        std::memcpy(scratch + p * sizeof(V), &a[order[p]], sizeof(V));
                    });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), kPermuteGrain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::memcpy(a.data() + r.begin(), scratch + r.begin() * sizeof(V), r.size() * sizeof(V));
                    });
}

template <typename V>
void compactArray(std::vector<V>& a, const std::vector<std::uint8_t>& remove) {
  std::size_t out = 0;
  for (std::size_t p = 0; p < a.size(); ++p)
    if (!remove[p]) a[out++] = a[p];
  a.resize(out);
}
}  // namespace

void MpmParticles::reserve(std::size_t n) {
  x.reserve(n);
  v.reserve(n);
  C.reserve(n);
  F.reserve(n);
  J.reserve(n);
  mass.reserve(n);
  volume0.reserve(n);
  count.reserve(n);
  material.reserve(n);
  id.reserve(n);
  magneticForce.reserve(n);
}

void MpmParticles::shrinkToFit() {
  x.shrink_to_fit();
  v.shrink_to_fit();
  C.shrink_to_fit();
  F.shrink_to_fit();
  J.shrink_to_fit();
  mass.shrink_to_fit();
  volume0.shrink_to_fit();
  count.shrink_to_fit();
  material.shrink_to_fit();
  id.shrink_to_fit();
  magneticForce.shrink_to_fit();
}

void MpmParticles::clear() {
  x.clear();
  v.clear();
  C.clear();
  F.clear();
  J.clear();
  mass.clear();
  volume0.clear();
  count.clear();
  material.clear();
  id.clear();
  magneticForce.clear();
}

std::size_t MpmParticles::add(const Vec3d& position, const Vec3d& velocity, double m, double v0, double n,
                              std::uint32_t mat) {
  require(isFinite(position), "MPM particle: position must be finite (m), got (", position.x, ", ", position.y, ", ",
          position.z, ")");
  require(isFinite(velocity), "MPM particle: velocity must be finite (m/s), got (", velocity.x, ", ", velocity.y, ", ",
          velocity.z, ")");
  require(std::isfinite(m) && m > 0, "MPM particle: mass must be a positive finite value in kg, got ", m);
  require(std::isfinite(v0) && v0 > 0, "MPM particle: volume must be a positive finite value in m^3, got ", v0);
  require(std::isfinite(n) && n >= 0, "MPM particle: micro-particle count n_p must be finite and >= 0, got ", n);
  x.push_back(position);
  v.push_back(velocity);
  C.push_back(Mat3d{});
  F.push_back(Mat3d::identity());
  J.push_back(1.0);
  mass.push_back(m);
  volume0.push_back(v0);
  count.push_back(n);
  material.push_back(mat);
  id.push_back(nextId++);
  magneticForce.push_back(Vec3d{});
  return x.size() - 1;
}

void MpmParticles::checkSizes() const {
  const std::size_t n = x.size();
  const bool ok = v.size() == n && C.size() == n && F.size() == n && J.size() == n && mass.size() == n &&
                  volume0.size() == n && count.size() == n && material.size() == n && id.size() == n &&
                  magneticForce.size() == n;
  require(ok, "MPM particles: every array must have ", n, " entries (the size of x); got v ", v.size(), ", C ",
          C.size(), ", F ", F.size(), ", J ", J.size(), ", mass ", mass.size(), ", volume0 ", volume0.size(),
          ", count ", count.size(), ", material ", material.size(), ", id ", id.size(), ", magneticForce ",
          magneticForce.size());
}

std::size_t MpmParticles::removeFlagged(const std::vector<std::uint8_t>& remove) {
  checkSizes();
  require(remove.size() == size(), "MPM particles: removal flags have ", remove.size(), " entries for ", size(),
          " particles");
  std::size_t removed = 0;
  for (std::uint8_t r : remove) removed += r != 0;
  if (removed == 0) return 0;
  compactArray(x, remove);
  compactArray(v, remove);
  compactArray(C, remove);
  compactArray(F, remove);
  compactArray(J, remove);
  compactArray(mass, remove);
  compactArray(volume0, remove);
  compactArray(count, remove);
  compactArray(material, remove);
  compactArray(id, remove);
  compactArray(magneticForce, remove);
  return removed;
}

void MpmParticles::permute(const std::vector<std::uint32_t>& order) {
  checkSizes();
  require(order.size() == size(), "MPM particles: permutation has ", order.size(), " entries for ", size(),
          " particles");
  std::vector<std::uint8_t> seen(order.size(), 0);
  for (std::uint32_t o : order) {
    require(o < order.size() && !seen[o], "MPM particles: the order is not a permutation (entry ", o, ")");
    seen[o] = 1;
  }
  // Not zeroed: the gather writes every byte it later reads. Fresh on every
  // sort, so on 2 MiB pages where the system has them (kept_capacity.h).
  const std::unique_ptr<unsigned char[]> scratch(new unsigned char[order.size() * sizeof(Mat3d)]);
  adviseHugePages(scratch.get(), order.size() * sizeof(Mat3d));
  static_assert(sizeof(Mat3d) >= sizeof(Vec3d) && sizeof(Mat3d) >= sizeof(std::uint64_t),
                "the scratch holds the widest attribute");
  permuteArray(x, order, scratch.get());
  permuteArray(v, order, scratch.get());
  permuteArray(C, order, scratch.get());
  permuteArray(F, order, scratch.get());
  permuteArray(J, order, scratch.get());
  permuteArray(mass, order, scratch.get());
  permuteArray(volume0, order, scratch.get());
  permuteArray(count, order, scratch.get());
  permuteArray(material, order, scratch.get());
  permuteArray(id, order, scratch.get());
  permuteArray(magneticForce, order, scratch.get());
}

double MpmParticles::totalMass() const {
  return deterministicSum<double>(size(), [&](std::size_t p) { return mass[p]; });
}

Vec3d MpmParticles::linearMomentum() const {
  return deterministicSum<Vec3d>(size(), [&](std::size_t p) { return mass[p] * v[p]; });
}

Vec3d MpmParticles::angularMomentum(double dx) const {
  const double s = 0.25 * dx * dx;
  return deterministicSum<Vec3d>(size(), [&](std::size_t p) {
    const Mat3d& c = C[p];
    const Vec3d spin{c(2, 1) - c(1, 2), c(0, 2) - c(2, 0), c(1, 0) - c(0, 1)};
    return cross(x[p], mass[p] * v[p]) + (mass[p] * s) * spin;
  });
}

Vec3d MpmParticles::centreOfMass() const {
  const double m = totalMass();
  if (!(m > 0)) return {};
  return deterministicSum<Vec3d>(size(), [&](std::size_t p) { return mass[p] * x[p]; }) / m;
}

}  // namespace mpm
}  // namespace lodestone
