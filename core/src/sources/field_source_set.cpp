#include "lodestone/core/sources/field_source_set.h"

#include <utility>

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace sources {

FieldSourceSet::FieldSourceSet(const FieldSourceSet& other) : FieldSource(other) {
  sources_.reserve(other.sources_.size());
  for (const auto& s : other.sources_) sources_.push_back(s->clone());
}

FieldSourceSet& FieldSourceSet::operator=(const FieldSourceSet& other) {
  if (this != &other) {
    FieldSourceSet copy(other);
    sources_ = std::move(copy.sources_);
  }
  return *this;
}

void FieldSourceSet::add(std::unique_ptr<FieldSource> source) {
  require(source != nullptr, "field source set: cannot add a null source (source ", size(), ")");
  sources_.push_back(std::move(source));
}

void FieldSourceSet::add(const FieldSource& source) { sources_.push_back(source.clone()); }

FieldSource& FieldSourceSet::source(std::size_t i) {
  require(i < sources_.size(), "field source set: index ", i, " out of range (size ", size(), ")");
  return *sources_[i];
}

const FieldSource& FieldSourceSet::source(std::size_t i) const {
  require(i < sources_.size(), "field source set: index ", i, " out of range (size ", size(), ")");
  return *sources_[i];
}

Vec3d FieldSourceSet::field(const Vec3d& x, double t) const {
  Vec3d H;
  for (const auto& s : sources_) H += s->field(x, t);
  return H;
}

Vec3d FieldSourceSet::magnetization(const Vec3d& x, double t) const {
  Vec3d M;
  for (const auto& s : sources_) M += s->magnetization(x, t);
  return M;
}

Vec3d FieldSourceSet::exteriorContinuation(const Vec3d& x, double t) const {
  Vec3d c;
  for (const auto& s : sources_) c += s->exteriorContinuation(x, t);
  return c;
}

void FieldSourceSet::accumulateField(const Vec3d* x, std::size_t count, double t,
                                     Vec3d* out) const {
  for (const auto& s : sources_) s->accumulateField(x, count, t, out);
}

bool FieldSourceSet::appendFieldSignature(double t, std::vector<double>& out) const {
  out.push_back(double(sources_.size()));
  for (const auto& s : sources_)
    if (!s->appendFieldSignature(t, out)) return false;
  return true;
}

bool FieldSourceSet::isUniform() const {
  for (const auto& s : sources_)
    if (!s->isUniform()) return false;
  return true;
}

std::string FieldSourceSet::describe() const {
  std::string d = concat(size(), size() == 1 ? " field source" : " field sources");
  for (std::size_t i = 0; i < sources_.size(); ++i)
    d += concat(i == 0 ? ": [" : "; [", i, "] ", sources_[i]->describe());
  return d;
}

std::unique_ptr<FieldSource> FieldSourceSet::clone() const {
  return std::make_unique<FieldSourceSet>(*this);
}

}  // namespace sources
}  // namespace lodestone
