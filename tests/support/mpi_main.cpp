// SPDX-License-Identifier: MIT
// GoogleTest main under MPI: every rank runs the tests; only rank 0 prints.
#include <gtest/gtest.h>
#include <mpi.h>
#if defined(TESSERA_HAVE_PETSC)
#include <petscsys.h>
#endif

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
#if defined(TESSERA_HAVE_PETSC)
  PetscInitializeNoArguments();  // the flow solver's tests need it; PETSc leaves MPI to us
#endif
  ::testing::InitGoogleTest(&argc, argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  int failed = RUN_ALL_TESTS();
  MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
#if defined(TESSERA_HAVE_PETSC)
  PetscFinalize();
#endif
  MPI_Finalize();
  return failed;
}
