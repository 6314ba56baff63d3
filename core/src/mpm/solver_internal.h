#pragma once
// What the MPM solver's source files share (solver.cpp, solver_magnetic.cpp):
// the applied field its stages see.
#include <cstddef>

#include "lodestone/core/mpm/solver.h"

namespace lodestone {
inline namespace mpm {

// ---------------------------------------------------------------------------
// The applied field the stage sees: the user's sources plus the magnets.

class MpmSolver::SceneField final : public FieldSource {
 public:
  SceneField(const FieldSourceSet& sources, const std::vector<std::unique_ptr<MagnetSource>>& magnets)
      : sources_(sources), magnets_(magnets) {}

  Vec3d field(const Vec3d& x, double t) const override {
    Vec3d H = sources_.field(x, t);
    for (const auto& m : magnets_) H += m->field(x, t);
    return H;
  }
  Vec3d magnetization(const Vec3d& x, double t) const override {
    Vec3d M = sources_.magnetization(x, t);
    for (const auto& m : magnets_) M += m->magnetization(x, t);
    return M;
  }
  Vec3d exteriorContinuation(const Vec3d& x, double t) const override {
    Vec3d c = sources_.exteriorContinuation(x, t);
    for (const auto& m : magnets_) c += m->exteriorContinuation(x, t);
    return c;
  }
  void accumulateField(const Vec3d* x, std::size_t count, double t, Vec3d* out) const override {
    sources_.accumulateField(x, count, t, out);
    for (const auto& m : magnets_) m->accumulateField(x, count, t, out);
  }
  bool isUniform() const override { return magnets_.empty() && sources_.isUniform(); }
  bool appendFieldSignature(double t, std::vector<double>& out) const override {
    if (!sources_.appendFieldSignature(t, out)) return false;
    out.push_back(double(magnets_.size()));
    for (const auto& m : magnets_)
      if (!m->appendFieldSignature(t, out)) return false;
    return true;
  }
  std::string describe() const override {
    return concat(sources_.describe(), "; plus ", magnets_.size(), " moving magnet(s)");
  }
  std::unique_ptr<FieldSource> clone() const override {
    auto set = std::make_unique<FieldSourceSet>(sources_);
    for (const auto& m : magnets_) set->add(*m);
    return set;
  }
  bool empty() const { return sources_.empty() && magnets_.empty(); }

 private:
  const FieldSourceSet& sources_;
  const std::vector<std::unique_ptr<MagnetSource>>& magnets_;
};

}  // namespace mpm
}  // namespace lodestone
