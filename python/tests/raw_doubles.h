#pragma once
// Raw float64 files (numpy's ndarray.tofile / np.fromfile) for the C++
// programs the Python tests and benchmark compare against.
#include <cstdio>
#include <string>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone::python {

inline std::vector<double> readDoubles(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw Error(concat("cannot open '", path, "'"));
  std::vector<double> v;
  double buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, sizeof(double), 4096, f)) > 0) v.insert(v.end(), buf, buf + n);
  std::fclose(f);
  return v;
}

/// A file of x, y, z triples as Vec3d.
inline std::vector<Vec3d> readVec3s(const std::string& path) {
  const std::vector<double> xs = readDoubles(path);
  std::vector<Vec3d> x(xs.size() / 3);
  for (std::size_t p = 0; p < x.size(); ++p) x[p] = {xs[3 * p], xs[3 * p + 1], xs[3 * p + 2]};
  return x;
}

inline void writeDoubles(const std::string& path, const double* data, std::size_t count) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || std::fwrite(data, sizeof(double), count, f) != count) throw Error(concat("cannot write '", path, "'"));
  std::fclose(f);
}

}  // namespace lodestone::python
