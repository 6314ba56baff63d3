#pragma once
// The node-centred Cartesian grid shared by the MPM and the magnetic stage:
// node (i,j,k) sits at origin + dx*(i,j,k). Cells are the boxes between nodes.
// Data lives in contiguous arrays with x fastest; views are non-owning so the
// same kernels serve our storage, a host's memory or a GPU mirror. Algorithms
// take views, never DenseGrid, so a sparse (tiled or VDB-backed) store only has
// to hand out dense views of the blocks it holds.
#include <cmath>
#include <cstddef>
#include <algorithm>
#include <cstdint>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/kept_capacity.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace base {

struct Index3 {
  int i = 0, j = 0, k = 0;
  constexpr int operator[](int a) const { return a == 0 ? i : (a == 1 ? j : k); }
  friend constexpr bool operator==(const Index3& a, const Index3& b) {
    return a.i == b.i && a.j == b.j && a.k == b.k;
  }
};

struct GridSpec {
  Vec3d origin;  ///< world position of node (0,0,0), m
  double dx = 0; ///< node spacing, m
  Index3 dims;   ///< number of nodes along x, y, z (each >= 2)

  std::size_t nodeCount() const {
    return std::size_t(dims.i) * std::size_t(dims.j) * std::size_t(dims.k);
  }
  Index3 cellDims() const { return {dims.i - 1, dims.j - 1, dims.k - 1}; }
  std::size_t cellCount() const {
    return std::size_t(dims.i - 1) * std::size_t(dims.j - 1) * std::size_t(dims.k - 1);
  }
  std::size_t index(int i, int j, int k) const {
    return std::size_t(i) + std::size_t(dims.i) * (std::size_t(j) + std::size_t(dims.j) * std::size_t(k));
  }
  std::size_t cellIndex(int i, int j, int k) const {
    return std::size_t(i) +
           std::size_t(dims.i - 1) * (std::size_t(j) + std::size_t(dims.j - 1) * std::size_t(k));
  }
  Vec3d nodePosition(int i, int j, int k) const {
    return {origin.x + dx * i, origin.y + dx * j, origin.z + dx * k};
  }
  /// World position of the last node, m.
  Vec3d maxCorner() const { return nodePosition(dims.i - 1, dims.j - 1, dims.k - 1); }
  /// (i, j, k) is a node of this grid.
  bool hasNode(int i, int j, int k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < dims.i && j < dims.j && k < dims.k;
  }
  bool isBoundaryNode(int i, int j, int k) const {
    return i == 0 || j == 0 || k == 0 || i == dims.i - 1 || j == dims.j - 1 || k == dims.k - 1;
  }
  /// Calls fn(i, j, k) for each boundary node of layer k, in index order:
  /// every node of a row on the k or j faces, the two ends of the others.
  template <typename Fn>
  void forEachBoundaryNodeOfLayer(int k, const Fn& fn) const {
    for (int j = 0; j < dims.j; ++j) {
      const bool faceRow = k == 0 || k == dims.k - 1 || j == 0 || j == dims.j - 1;
      for (int i = 0; i < dims.i; i += (faceRow || i == dims.i - 1) ? 1 : dims.i - 1) fn(i, j, k);
    }
  }
  /// Calls fn(i, j, k) for each boundary node, in index order.
  template <typename Fn>
  void forEachBoundaryNode(const Fn& fn) const {
    for (int k = 0; k < dims.k; ++k) forEachBoundaryNodeOfLayer(k, fn);
  }
  /// Cell volume dx^3, m^3.
  double cellVolume() const { return dx * dx * dx; }

  /// Throws InvalidArgument naming `what` and the bad value.
  void validate(const char* what = "grid") const {
    require(std::isfinite(dx) && dx > 0, what, ": node spacing dx must be a positive finite length in m, got ", dx);
    require(isFinite(origin), what, ": origin must be finite, got (", origin.x, ", ", origin.y, ", ", origin.z, ")");
    require(dims.i >= 2 && dims.j >= 2 && dims.k >= 2, what, ": at least 2 nodes per axis are needed, got ",
            dims.i, " x ", dims.j, " x ", dims.k);
    // Guard the flat index against overflow (2^40 nodes is far beyond memory anyway).
    require(double(dims.i) * dims.j * dims.k < 1.1e12, what, ": ", dims.i, " x ", dims.j, " x ", dims.k,
            " nodes is too many");
  }
  friend bool operator==(const GridSpec& a, const GridSpec& b) {
    return a.origin == b.origin && a.dx == b.dx && a.dims == b.dims;
  }
  /// Whether every node of `inner` is a node of this grid (same lattice).
  bool contains(const GridSpec& inner) const {
    for (int a = 0; a < 3; ++a) {
      const double lo = (inner.origin[a] - origin[a]) / dx;
      if (lo < -1e-9 || lo + inner.dims[a] - 1 > dims[a] - 1 + 1e-9) return false;
    }
    return true;
  }
  /// Whether the boxes of this grid's nodes and of `other`'s meet (share a
  /// node, on one lattice).
  bool meets(const GridSpec& other) const {
    for (int a = 0; a < 3; ++a) {
      const double lo = origin[a], hi = lo + dx * (dims[a] - 1);
      const double otherLo = other.origin[a], otherHi = otherLo + other.dx * (other.dims[a] - 1);
      if (hi < otherLo - 1e-9 * dx || otherHi < lo - 1e-9 * dx) return false;
    }
    return true;
  }
};

/// A non-owning view of one value per grid node.
template <typename T>
struct GridView {
  T* data = nullptr;
  GridSpec spec;

  std::size_t size() const { return spec.nodeCount(); }
  T& operator[](std::size_t n) const { return data[n]; }
  T& operator()(int i, int j, int k) const { return data[spec.index(i, j, k)]; }
  operator GridView<const T>() const { return {data, spec}; }
};

/// Owning dense storage of one value per node.
template <typename T>
class DenseGrid {
 public:
  DenseGrid() = default;
  explicit DenseGrid(const GridSpec& spec, const T& value = T{}) { reset(spec, value); }

  void reset(const GridSpec& spec, const T& value = T{}) {
    spec.validate();
    spec_ = spec;
    assignKeepingCapacity(data_, spec.nodeCount(), value);
  }
  void fill(const T& value) { std::fill(data_.begin(), data_.end(), value); }

  const GridSpec& spec() const { return spec_; }
  std::size_t size() const { return data_.size(); }
  bool empty() const { return data_.empty(); }
  T* data() { return data_.data(); }
  const T* data() const { return data_.data(); }
  T& operator[](std::size_t n) { return data_[n]; }
  const T& operator[](std::size_t n) const { return data_[n]; }
  T& operator()(int i, int j, int k) { return data_[spec_.index(i, j, k)]; }
  const T& operator()(int i, int j, int k) const { return data_[spec_.index(i, j, k)]; }
  GridView<T> view() { return {data_.data(), spec_}; }
  GridView<const T> view() const { return {data_.data(), spec_}; }
  std::vector<T>& values() { return data_; }
  const std::vector<T>& values() const { return data_; }

 private:
  GridSpec spec_;
  std::vector<T> data_;
};

}  // namespace base
}  // namespace lodestone
