#pragma once
// Applied-field sources: closed-form fields of coils and permanent magnets.
// They make the applied field H_ext of PHYSICS.md section 2, which is curl-free
// and divergence-free outside the source bodies. Sources are immutable apart
// from their pose and are safe to evaluate from many threads at once.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lodestone/core/base/vec3.h"

namespace lodestone {
inline namespace sources {

class FieldSource {
 public:
  FieldSource();
  /// A copy is a new instance (a new instanceId()).
  FieldSource(const FieldSource&);
  FieldSource& operator=(const FieldSource&);
  virtual ~FieldSource() = default;

  /// Applied field H (A/m) at world position x (m) and time t (s).
  virtual Vec3d field(const Vec3d& x, double t) const = 0;

  /// Permanent magnetization (A/m) carried by the source body at x; zero
  /// outside the body and for sources without a body (uniform field, dipole).
  virtual Vec3d magnetization(const Vec3d& /*x*/, double /*t*/) const { return {}; }

  /// Inside a source body, what to add to field(x, t) (A/m) to continue the
  /// field outside the body through its nearest face: (M.n) n for a
  /// uniformly magnetized body with outward face normal n, half that on the
  /// surface (where field() is the mean of the two sides), zero outside and
  /// for sources without a body. field + exteriorContinuation is continuous
  /// across the faces. Material lies outside magnets, but the transfer
  /// spreads it onto grid nodes up to 1.5 cells away, some of them inside a
  /// magnet: this is the field that material sees there.
  virtual Vec3d exteriorContinuation(const Vec3d& /*x*/, double /*t*/) const { return {}; }

  /// Adds the field at `count` points to `out` (A/m). Override for speed.
  virtual void accumulateField(const Vec3d* x, std::size_t count, double t, Vec3d* out) const {
    for (std::size_t n = 0; n < count; ++n) out[n] += field(x[n], t);
  }

  /// True when the field is the same everywhere (at any fixed time).
  virtual bool isUniform() const { return false; }

  /// One line naming the source and its parameters with units.
  virtual std::string describe() const = 0;

  /// Appends to `out` numbers that fix this instance's field at time t (s):
  /// two calls that append the same numbers give bit-identical fields
  /// everywhere, so a caller may reuse values it computed before (the
  /// magnetic stage reuses H_ext on its grid nodes). The numbers include
  /// instanceId(); sources append their pose and time factor s(t), their
  /// other parameters being immutable. Returns false (the default, for
  /// sources that cannot tell) when nothing may be reused.
  virtual bool appendFieldSignature(double /*t*/, std::vector<double>& /*out*/) const { return false; }

  /// Unique per constructed or copied source in this process.
  std::uint64_t instanceId() const { return instanceId_; }

  virtual std::unique_ptr<FieldSource> clone() const = 0;

 private:
  std::uint64_t instanceId_;
};

}  // namespace sources
}  // namespace lodestone
