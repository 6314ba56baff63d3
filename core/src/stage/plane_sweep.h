#pragma once
// What the plane-by-plane passes of the stage share (nodal_field.cpp:
// the projected gradient; magnetic_force.cpp: the force's spread): chunks of
// z planes in parallel, each thread with a few planes of its own, and a
// window of the three planes around the current one of a quantity computed
// plane by plane (the planes a pass across z reads).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstddef>
#include <vector>

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace stage {

/// body(first, end, planes) for chunks [first, end) of the nz z planes, in
/// parallel; `planes` points at perThread planes of `plane` elements that
/// the calling thread owns for the chunk (in `storage`, kept between calls).
template <typename T, typename Body>
void forEachPlaneChunk(int nz, std::size_t plane, std::size_t perThread, std::vector<T>& storage,
                       const Body& body) {
  const std::size_t threads = std::size_t(tbb::this_task_arena::max_concurrency());
  storage.resize(threads * perThread * plane);  // every value is written before it is read
  tbb::parallel_for(tbb::blocked_range<int>(0, nz, 16), [&](const tbb::blocked_range<int>& r) {
    const std::size_t slot = std::size_t(tbb::this_task_arena::current_thread_index());
    require(slot < threads, "plane sweep: thread index ", slot, " outside the arena's ", threads);
    body(r.begin(), r.end(), storage.data() + slot * perThread * plane);
  });
}

/// Planes j - 1, j, j + 1 of a quantity computed plane by plane, in three
/// planes of storage (plane j in slot j % 3): advanceTo(k, fill) computes,
/// by fill(j, dst), the planes up to k + 1 not computed yet, starting from
/// first - 1 (the chunk's halo).
template <typename T>
class PlaneWindow {
 public:
  PlaneWindow(T* storage, std::size_t plane, int first, int nz)
      : slots_{storage, storage + plane, storage + 2 * plane}, next_(std::max(first - 1, 0)), nz_(nz) {}
  template <typename Fill>
  void advanceTo(int k, const Fill& fill) {
    for (; next_ <= std::min(k + 1, nz_ - 1); ++next_) fill(next_, slots_[next_ % 3]);
  }
  /// Plane j, or nullptr outside the grid.
  const T* at(int j) const { return j >= 0 && j < nz_ ? slots_[j % 3] : nullptr; }

 private:
  T* slots_[3];
  int next_, nz_;
};

}  // namespace stage
}  // namespace lodestone
