#include "arrays.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <sstream>

#include "lodestone/core/base/error.h"

namespace lodestone::python {

std::string shapeText(const py::array& a) {
  std::ostringstream os;
  os << "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) os << (d ? ", " : "") << a.shape(d);
  if (a.ndim() == 1) os << ",";
  os << ")";
  return os.str();
}

namespace {

// The object as a numpy array of float32 or float64 (anything else: ValueError).
py::array asFloatArray(const py::handle& object, const char* name) {
  py::array a;
  if (py::isinstance<py::array>(object)) {
    a = py::reinterpret_borrow<py::array>(object);
  } else {
    // Lists and tuples: numpy decides the dtype (integers become int64, which
    // is converted below like float32; anything not numeric is refused).
    a = py::array::ensure(object);
    if (!a) throw py::value_error(concat(name, ": expected a numpy array or a sequence of numbers"));
    if (a.dtype().kind() == 'i' || a.dtype().kind() == 'u') a = py::array_t<double>::ensure(a);
  }
  const char kind = a.dtype().kind();
  const py::ssize_t size = a.itemsize();
  if (kind != 'f' || (size != 4 && size != 8))
    throw py::value_error(concat(name, ": expected float32 or float64 values, got dtype ",
                                 std::string(py::str(a.dtype()))));
  if (a.dtype().byteorder() == '>')
    throw py::value_error(concat(name, ": expected native (little-endian) byte order, got dtype ",
                                 std::string(py::str(a.dtype()))));
  return a;
}

template <typename T>
double at(const py::array& a, py::ssize_t i, py::ssize_t j, py::ssize_t k, int ndim) {
  const char* base = static_cast<const char*>(a.data());
  py::ssize_t off = i * a.strides(0);
  if (ndim > 1) off += j * a.strides(1);
  if (ndim > 2) off += k * a.strides(2);
  T v;
  std::memcpy(&v, base + off, sizeof v);  // unaligned views are legal in numpy
  return double(v);
}

double element(const py::array& a, py::ssize_t i, py::ssize_t j = 0, py::ssize_t k = 0) {
  const int ndim = int(a.ndim());
  return a.itemsize() == 8 ? at<double>(a, i, j, k, ndim) : at<float>(a, i, j, k, ndim);
}

bool isNativeDouble(const py::array& a) {
  return a.dtype().kind() == 'f' && a.itemsize() == 8 && a.dtype().byteorder() != '>' &&
         reinterpret_cast<std::uintptr_t>(a.data()) % alignof(double) == 0;
}

std::pair<const void*, const void*> byteRange(const py::array& a) {
  if (a.size() == 0) return {nullptr, nullptr};
  const char* lo = static_cast<const char*>(a.data());
  const char* hi = lo;
  for (py::ssize_t d = 0; d < a.ndim(); ++d) {
    const py::ssize_t span = (a.shape(d) - 1) * a.strides(d);
    if (span < 0) lo += span; else hi += span;
  }
  return {lo, hi + a.itemsize()};
}

}  // namespace

Vec3Input::Vec3Input(const py::handle& object, const char* name, long expectCount) {
  array_ = asFloatArray(object, name);
  if (array_.ndim() != 2 || array_.shape(1) != 3)
    throw py::value_error(concat(name, ": expected an array of shape (N, 3), got shape ", shapeText(array_)));
  size_ = std::size_t(array_.shape(0));
  if (expectCount >= 0 && size_ != std::size_t(expectCount))
    throw py::value_error(concat(name, ": expected ", expectCount, " rows (one per particle), got shape ",
                                 shapeText(array_)));
  std::tie(begin_, end_) = byteRange(array_);
  if (isNativeDouble(array_) && array_.strides(1) == 8 && (array_.strides(0) == 24 || size_ <= 1)) {
    data_ = static_cast<const Vec3d*>(array_.data());
    return;
  }
  copy_.resize(size_);
  for (std::size_t p = 0; p < size_; ++p)
    copy_[p] = {element(array_, py::ssize_t(p), 0), element(array_, py::ssize_t(p), 1),
                element(array_, py::ssize_t(p), 2)};
  data_ = copy_.data();
}

ScalarInput::ScalarInput(const py::handle& object, const char* name, long expectCount) {
  array_ = asFloatArray(object, name);
  if (array_.ndim() != 1)
    throw py::value_error(concat(name, ": expected an array of shape (N,), got shape ", shapeText(array_)));
  size_ = std::size_t(array_.shape(0));
  if (expectCount >= 0 && size_ != std::size_t(expectCount))
    throw py::value_error(concat(name, ": expected shape (", expectCount, ",) (one value per particle), got shape ",
                                 shapeText(array_)));
  std::tie(begin_, end_) = byteRange(array_);
  if (isNativeDouble(array_) && (array_.strides(0) == 8 || size_ <= 1)) {
    data_ = static_cast<const double*>(array_.data());
    return;
  }
  copy_.resize(size_);
  for (std::size_t p = 0; p < size_; ++p) copy_[p] = element(array_, py::ssize_t(p));
  data_ = copy_.data();
}

GridInput::GridInput(const py::handle& object, const char* name, const GridSpec& spec) : spec_(spec) {
  array_ = asFloatArray(object, name);
  const Index3 d = spec.dims;
  if (array_.ndim() != 3 || array_.shape(0) != d.i || array_.shape(1) != d.j || array_.shape(2) != d.k)
    throw py::value_error(concat(name, ": expected an array of shape (", d.i, ", ", d.j, ", ", d.k,
                                 ") (one value per grid node), got shape ", shapeText(array_)));
  if (isNativeDouble(array_) && array_.strides(0) == 8 && array_.strides(1) == 8 * d.i &&
      array_.strides(2) == py::ssize_t(8) * d.i * d.j) {
    data_ = static_cast<const double*>(array_.data());
    return;
  }
  copy_.resize(spec.nodeCount());
  for (int k = 0; k < d.k; ++k)
    for (int j = 0; j < d.j; ++j)
      for (int i = 0; i < d.i; ++i) copy_[spec.index(i, j, k)] = element(array_, i, j, k);
  data_ = copy_.data();
}

py::array_t<double> vec3Output(const py::object& out, std::size_t count,
                               const std::vector<std::pair<const char*, std::pair<const void*, const void*>>>& inputs,
                               Vec3d*& data) {
  if (out.is_none()) {
    py::array_t<double> a({py::ssize_t(count), py::ssize_t(3)});
    data = reinterpret_cast<Vec3d*>(a.mutable_data());
    return a;
  }
  if (!py::isinstance<py::array>(out)) throw py::value_error("out: expected a numpy array of shape (N, 3)");
  py::array a = py::reinterpret_borrow<py::array>(out);
  if (a.ndim() != 2 || a.shape(0) != py::ssize_t(count) || a.shape(1) != 3)
    throw py::value_error(concat("out: expected an array of shape (", count, ", 3), got shape ", shapeText(a)));
  if (!isNativeDouble(a) || a.strides(1) != 8 || (a.strides(0) != 24 && count > 1))
    throw py::value_error(concat("out: expected a C-contiguous float64 array, got dtype ",
                                 std::string(py::str(a.dtype())), " with strides (", a.strides(0), ", ",
                                 a.strides(1), ")"));
  if (!a.writeable()) throw py::value_error("out: the array is read-only");
  const auto range = byteRange(a);
  for (const auto& [name, r] : inputs)
    if (r.first && range.first && r.first < range.second && range.first < r.second)
      throw py::value_error(concat("out: shares memory with ", name, "; pass a separate array"));
  data = reinterpret_cast<Vec3d*>(a.mutable_data());
  return py::array_t<double>(a);
}

py::array gridView(GridView<const double> view, const py::handle& owner) {
  if (!view.data) throw py::value_error("no field yet: the stage has not run");
  const Index3 d = view.spec.dims;
  const py::ssize_t s = sizeof(double);
  py::array a(py::dtype::of<double>(), {py::ssize_t(d.i), py::ssize_t(d.j), py::ssize_t(d.k)},
              {s, s * d.i, s * d.i * d.j}, view.data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

py::array gridView(GridView<const Vec3d> view, const py::handle& owner) {
  if (!view.data) throw py::value_error("no field yet: the stage has not run");
  const Index3 d = view.spec.dims;
  const py::ssize_t s = sizeof(Vec3d);
  py::array a(py::dtype::of<double>(), {py::ssize_t(d.i), py::ssize_t(d.j), py::ssize_t(d.k), py::ssize_t(3)},
              {s, s * d.i, s * d.i * d.j, py::ssize_t(sizeof(double))}, reinterpret_cast<const double*>(view.data),
              owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

py::array_t<double> copyToNumpy(const std::vector<Vec3d>& values) {
  py::array_t<double> a({py::ssize_t(values.size()), py::ssize_t(3)});
  std::copy(values.begin(), values.end(), reinterpret_cast<Vec3d*>(a.mutable_data()));
  return a;
}

Vec3d toVec3(const py::handle& object, const char* name) {
  py::array a = asFloatArray(object, name);
  if (a.ndim() != 1 || a.shape(0) != 3)
    throw py::value_error(concat(name, ": expected 3 numbers (shape (3,)), got shape ", shapeText(a)));
  return {element(a, 0), element(a, 1), element(a, 2)};
}

py::array_t<double> fromVec3(const Vec3d& v) {
  py::array_t<double> a(3);
  double* p = a.mutable_data();
  p[0] = v.x;
  p[1] = v.y;
  p[2] = v.z;
  return a;
}

}  // namespace lodestone::python
