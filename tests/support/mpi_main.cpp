// SPDX-License-Identifier: MIT
// GoogleTest main under MPI: every rank runs the tests; rank 0 prints the usual report, the others
// only their failed assertions (with the rank), so that a failure on any rank can be read.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdio>
#if defined(TESSERA_HAVE_PETSC)
#include <petscsys.h>
#endif

namespace {

class FailurePrinter : public ::testing::EmptyTestEventListener {
 public:
  explicit FailurePrinter(int rank) : rank_(rank) {}
  void OnTestPartResult(const ::testing::TestPartResult& r) override {
    if (r.failed())
      std::fprintf(stderr, "[rank %d] %s:%d: Failure\n%s\n", rank_, r.file_name() ? r.file_name() : "?",
                   r.line_number(), r.message());
  }

 private:
  int rank_;
};

}  // namespace

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
    listeners.Append(new FailurePrinter(rank));
  }
  int failed = RUN_ALL_TESTS();
  MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
#if defined(TESSERA_HAVE_PETSC)
  PetscFinalize();
#endif
  MPI_Finalize();
  return failed;
}
