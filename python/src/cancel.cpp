#include "cancel.h"

namespace lodestone::python {

Hook::~Hook() = default;

void Hook::rethrow() {
  if (!error_) return;
  py::error_already_set e = std::move(*error_);
  error_.reset();
  throw e;
}

}  // namespace lodestone::python
