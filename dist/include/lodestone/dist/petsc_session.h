#pragma once
// MPI and PETSc for a program's lifetime.

namespace lodestone {
inline namespace dist {

/// PetscInitialize on construction, PetscFinalize on destruction (which also
/// initializes and finalizes MPI when the program has not). PETSc options
/// come from argv and the PETSC_OPTIONS environment variable. Throws Error
/// when PETSc cannot start. Restores the allocator's thresholds first
/// (allocator_defaults.h).
class PetscSession {
 public:
  PetscSession(int* argc, char*** argv);
  ~PetscSession();
  PetscSession(const PetscSession&) = delete;
  PetscSession& operator=(const PetscSession&) = delete;
};

}  // namespace dist
}  // namespace lodestone
