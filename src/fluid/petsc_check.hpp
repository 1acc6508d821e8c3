// SPDX-License-Identifier: MIT
// PETSc calls return an error code; a non-zero one becomes a RunError naming the call.
#pragma once
#include <petscsys.h>

#include <string>

#include "core/errors.hpp"

namespace tessera {

inline void petsc_check(PetscErrorCode ierr, const char* what) {
  if (ierr) throw RunError(std::string("PETSc error in ") + what + " (code " + std::to_string(int(ierr)) + ")");
}

}  // namespace tessera
