#include "lodestone/core/stage/induction_field.h"

#include <algorithm>
#include <cmath>

#include "lodestone/core/base/constants.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/parallel.h"
#include "lodestone/core/stage/magnetic_stage.h"

namespace lodestone {
inline namespace stage {

InductionField::InductionField(const FieldSource& sources, double time) : sources_(sources.clone()), time_(time) {
  require(std::isfinite(time), "induction field: time must be finite, got ", time, " s");
}

InductionField::InductionField(const FieldSource& sources, double time, DenseGrid<Vec3d> materialPart)
    : InductionField(sources, time) {
  if (!materialPart.empty()) materialPart.spec().validate("induction field: material grid");
  material_ = std::move(materialPart);
}

InductionField InductionField::ofStage(const MagneticForceStage& stage, const FieldSource& sources, double time) {
  const GridView<const Vec3d> B = stage.inductionField();
  require(B.data != nullptr && B.spec.nodeCount() > 0, "induction field: the magnetic stage has not run yet");
  DenseGrid<Vec3d> part(B.spec);
  const GridSpec& g = B.spec;
  const double solved = stage.time();
  parallelForEach(
      g.nodeCount(),
      [&](std::size_t m) {
        const int i = int(m % std::size_t(g.dims.i)), j = int((m / std::size_t(g.dims.i)) % std::size_t(g.dims.j)),
                  k = int(m / (std::size_t(g.dims.i) * std::size_t(g.dims.j)));
        const Vec3d x = g.nodePosition(i, j, k);
        part[m] = B[m] - kMu0 * (sources.field(x, solved) + sources.magnetization(x, solved));
      },
      1024);
  return InductionField(sources, time, std::move(part));
}

InductionField::InductionField(const InductionField& other)
    : sources_(other.sources_->clone()), time_(other.time_), material_(other.material_) {}

InductionField& InductionField::operator=(const InductionField& other) {
  if (this != &other) {
    sources_ = other.sources_->clone();
    time_ = other.time_;
    material_ = other.material_;
  }
  return *this;
}

Vec3d InductionField::sourcesPart(const Vec3d& x) const {
  return kMu0 * (sources_->field(x, time_) + sources_->magnetization(x, time_));
}

Vec3d InductionField::materialPart(const Vec3d& x) const {
  if (material_.empty()) return {};
  const GridSpec& g = material_.spec();
  const Vec3d u = (x - g.origin) / g.dx;
  int base[3];
  double w[3];
  for (int a = 0; a < 3; ++a) {
    const int n = g.dims[a];
    if (!(u[a] >= 0.0 && u[a] <= double(n - 1))) return {};  // outside the box (or NaN)
    base[a] = std::min(int(u[a]), n - 2);
    w[a] = u[a] - base[a];
  }
  Vec3d sum;
  for (int c = 0; c < 8; ++c) {
    const int di = c & 1, dj = (c >> 1) & 1, dk = (c >> 2) & 1;
    const double weight = (di ? w[0] : 1 - w[0]) * (dj ? w[1] : 1 - w[1]) * (dk ? w[2] : 1 - w[2]);
    sum += weight * material_(base[0] + di, base[1] + dj, base[2] + dk);
  }
  return sum;
}

Vec3d InductionField::operator()(const Vec3d& x) const { return sourcesPart(x) + materialPart(x); }

}  // namespace stage
}  // namespace lodestone
