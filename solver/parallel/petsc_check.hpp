// PETSc's error codes as exceptions, for the .cpp files of solver/parallel/ that call PETSc (the
// only ones that include its headers).
#pragma once

#include <petscsys.h>

#include <stdexcept>
#include <string>

namespace swmpm::parallel {

/// Throws when a PETSc call failed (PETSc has printed its own trace on stderr).
inline void petsc(PetscErrorCode code) {
  if (code != 0) throw std::runtime_error("PETSc error " + std::to_string(static_cast<int>(code)) + " (see above)");
}

}  // namespace swmpm::parallel
