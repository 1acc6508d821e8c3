// SPDX-License-Identifier: MIT
// What the blast's tests build (src/fracture): a bar of bonded tetrahedra, and a solver with its
// decomposition over a communicator.
#pragma once
#include <mpi.h>

#include <array>
#include <optional>

#include "fracture/fracture_solver.hpp"
#include "solid/gmsh_reader.hpp"

namespace tessera::test {

// A bar of nx x ny x nz cubes of side h, each split into 6 tetrahedra around its main diagonal
// (Freudenthal: conforming across the cubes).
inline TetMesh bar_mesh(int nx, int ny, int nz, double h) {
  TetMesh m;
  auto node = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) m.nodes.push_back({i * h, j * h, k * h});
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& p : perms) {
          int c[3] = {0, 0, 0};
          std::array<int, 4> t{};
          t[0] = node(i, j, k);
          for (int s = 0; s < 3; ++s) {
            c[p[s]] = 1;
            t[static_cast<std::size_t>(s) + 1] = node(i + c[0], j + c[1], k + c[2]);
          }
          m.tetrahedra.push_back(t);
        }
  return m;
}

// A block's solver on a decomposition of [lo, hi] over comm (no borehole).
struct FractureWorld {
  Decomposition decomp;
  FractureSolver solver;
  FractureWorld(MPI_Comm comm, const TetMesh& mesh, FractureSettings s, Vec3 lo, Vec3 hi)
      : decomp(comm, lo, hi), solver(decomp, build_bonded_block(mesh, s.density), s, std::nullopt) {}
};

}  // namespace tessera::test
