// SPDX-License-Identifier: MIT
// STL input: the surface of a tetrahedron written as ASCII and as binary reads back to the same
// 4 shared nodes and 4 triangles, scaled to metres; broken files fail with the file named.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/errors.hpp"
#include "solid/stl_reader.hpp"

namespace tessera {
namespace {

const double kV[4][3] = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {0, 0, 10}};
const int kT[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

std::string temp(const char* name) { return (std::filesystem::temp_directory_path() / name).string(); }

void expect_tetrahedron_surface(const TetMesh& m) {
  ASSERT_EQ(m.nodes.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 4u);
  for (int t = 0; t < 4; ++t)
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) EXPECT_DOUBLE_EQ(m.nodes[m.triangles[t][k]][d], kV[kT[t][k]][d] * 1e-3);
}

TEST(StlReader, AsciiAndBinaryGiveTheSameSharedMesh) {
  {
    std::ofstream o(temp("tessera_tet.stl"));
    o << "solid tet\n";
    for (const auto& t : kT) {
      o << " facet normal 0 0 0\n  outer loop\n";
      for (const int v : t) o << "   vertex " << kV[v][0] << " " << kV[v][1] << " " << kV[v][2] << "\n";
      o << "  endloop\n endfacet\n";
    }
    o << "endsolid tet\n";
  }
  expect_tetrahedron_surface(read_stl(temp("tessera_tet.stl"), 1e-3));  // file in mm
  {
    std::ofstream o(temp("tessera_tet_bin.stl"), std::ios::binary);
    char header[80] = "solid but binary";  // the size decides the format
    o.write(header, 80);
    const std::uint32_t n = 4;
    o.write(reinterpret_cast<const char*>(&n), 4);
    for (const auto& t : kT) {
      float rec[12] = {};
      for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 3; ++d) rec[3 + 3 * k + d] = static_cast<float>(kV[t[k]][d]);
      o.write(reinterpret_cast<const char*>(rec), 48);
      const std::uint16_t attr = 0;
      o.write(reinterpret_cast<const char*>(&attr), 2);
    }
  }
  expect_tetrahedron_surface(read_stl(temp("tessera_tet_bin.stl"), 1e-3));
}

TEST(StlReader, BrokenFilesNameTheFile) {
  {
    std::ofstream o(temp("tessera_broken.stl"));
    o << "solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 1 0 0\n endloop\n";
  }
  try {
    read_stl(temp("tessera_broken.stl"));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tessera_broken.stl"), std::string::npos);
  }
  EXPECT_THROW(read_stl(temp("tessera_missing.stl")), InputError);
}

}  // namespace
}  // namespace tessera
