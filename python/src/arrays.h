#pragma once
// numpy arrays in and out of the module. Inputs are read in place when they
// already have the C++ layout (float64, packed: an (N, 3) array of Vec3d is
// N*3 contiguous doubles), and copied otherwise (float32 converted, strided
// and non-contiguous views gathered). Wrong shapes and dtypes raise
// ValueError naming the argument, the expected and the actual shape.
// Outputs are new float64 arrays the C++ code writes into, or a caller's
// `out` array, which must be packed float64, writable and share no memory
// with an input.
#include <cstddef>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "lodestone/core/base/grid.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone::python {

namespace py = pybind11;

/// "(5, 2)".
std::string shapeText(const py::array& a);

/// An (N, 3) array of positions or vectors as Vec3d: in place when float64
/// and packed, else a converted copy. Keeps the numpy array alive.
class Vec3Input {
 public:
  /// `name` is the argument's name in messages; `expectCount` >= 0 fixes N.
  Vec3Input(const py::handle& object, const char* name, long expectCount = -1);
  const Vec3d* data() const { return data_; }
  std::size_t size() const { return size_; }
  /// The bytes [begin, end) of the numpy buffer this input reads.
  const void* begin() const { return begin_; }
  const void* end() const { return end_; }
  bool copied() const { return !copy_.empty() || size_ == 0; }

 private:
  py::array array_;
  std::vector<Vec3d> copy_;
  const Vec3d* data_ = nullptr;
  std::size_t size_ = 0;
  const void* begin_ = nullptr;
  const void* end_ = nullptr;
};

/// An (N,) array of scalars as doubles, the same rules as Vec3Input.
class ScalarInput {
 public:
  ScalarInput(const py::handle& object, const char* name, long expectCount = -1);
  const double* data() const { return data_; }
  std::size_t size() const { return size_; }
  const void* begin() const { return begin_; }
  const void* end() const { return end_; }

 private:
  py::array array_;
  std::vector<double> copy_;
  const double* data_ = nullptr;
  std::size_t size_ = 0;
  const void* begin_ = nullptr;
  const void* end_ = nullptr;
};

/// A node array of shape (nx, ny, nz) for `spec` (index [i, j, k] is node
/// (i, j, k)) as doubles with x fastest: in place when float64 and
/// Fortran-contiguous, else copied.
class GridInput {
 public:
  GridInput(const py::handle& object, const char* name, const GridSpec& spec);
  GridView<const double> view() const { return {data_, spec_}; }

 private:
  py::array array_;
  std::vector<double> copy_;
  const double* data_ = nullptr;
  GridSpec spec_;
};

/// A new (N, 3) float64 array, or the caller's `out` checked: shape (N, 3),
/// float64, C-contiguous, writable, and sharing no bytes with `inputs`
/// (name, begin, end). Returns the array; `data` points at its Vec3d storage.
py::array_t<double> vec3Output(const py::object& out, std::size_t count,
                               const std::vector<std::pair<const char*, std::pair<const void*, const void*>>>& inputs,
                               Vec3d*& data);

/// A read-only view of one value (or 3-vector) per node, shape (nx, ny, nz)
/// or (nx, ny, nz, 3), index [i, j, k] = node (i, j, k); it keeps `owner`
/// alive and shows its storage, not a copy.
py::array gridView(GridView<const double> view, const py::handle& owner);
py::array gridView(GridView<const Vec3d> view, const py::handle& owner);

/// New numpy arrays holding copies: (N, 3) float64 of Vec3d, (N,) of scalars.
py::array_t<double> copyToNumpy(const std::vector<Vec3d>& values);
template <typename T>
py::array_t<T> copyToNumpy(const std::vector<T>& values) {
  return py::array_t<T>(py::ssize_t(values.size()), values.data());
}

/// A 3-vector argument: a sequence or array of 3 numbers.
Vec3d toVec3(const py::handle& object, const char* name);
py::array_t<double> fromVec3(const Vec3d& v);

}  // namespace lodestone::python
