#include "lodestone/core/sources/field_source.h"

#include <atomic>

namespace lodestone {
inline namespace sources {

namespace {
std::uint64_t nextInstanceId() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}
}  // namespace

FieldSource::FieldSource() : instanceId_(nextInstanceId()) {}

FieldSource::FieldSource(const FieldSource&) : instanceId_(nextInstanceId()) {}

FieldSource& FieldSource::operator=(const FieldSource&) {
  instanceId_ = nextInstanceId();
  return *this;
}

}  // namespace sources
}  // namespace lodestone
