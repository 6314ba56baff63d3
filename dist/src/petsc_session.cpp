#include "lodestone/dist/petsc_session.h"

#include <petscsys.h>

#include "lodestone/core/base/error.h"
#include "lodestone/dist/allocator_defaults.h"

namespace lodestone {
inline namespace dist {

PetscSession::PetscSession(int* argc, char*** argv) {
  restoreAllocatorDefaults();
  if (PetscInitialize(argc, argv, nullptr, nullptr) != 0) throw Error("PETSc could not be initialized");
}

PetscSession::~PetscSession() { PetscFinalize(); }

}  // namespace dist
}  // namespace lodestone
