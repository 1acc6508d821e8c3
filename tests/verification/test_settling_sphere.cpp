// SPDX-License-Identifier: MIT
// A sphere settling in a viscous liquid against ten Cate et al. (2002, Phys. Fluids 14, 4012), case
// E3: a 15 mm nylon sphere (1120 kg/m^3) in silicone oil (962 kg/m^3, 0.113 Pa s) in a closed
// 100 x 100 x 160 mm box, measured terminal speed 0.091 m/s (Re 11.6). The shipped case
// (cases/coupled/settling_sphere.yaml) on 4.2 and 8.4 cells per diameter: the largest downward
// speed over 0.8 s must come within 7 % of the measurement on both grids. The bound: the finest run
// made (16.8 cells per diameter, seed's correction, 1.77 million cells, docs/validation.md) is 5.1 %
// slow, which is what the grid converges to; 2 % is left for the partly covered cells of the coarse
// grids. (Until 2026-11-30, with the seed's per-step correction, the bound was 5 % on the finer grid
// with the error falling with the grid; the rate's drag (theory C4c) gives -3.9 % and -6.0 %.)
// For scale: Schiller-Naumann's drag gives 0.094 m/s unbounded.
// tools/settling_sphere.py runs the study with the third grid (16.8 cells per diameter) and draws
// the approach to terminal speed.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "support/scene_runs.hpp"

using namespace tessera;

namespace {

std::string case_text() {
  return test::file_text(std::string(TESSERA_SOURCE_DIR) + "/cases/coupled/settling_sphere.yaml");
}

// The largest downward speed of the sphere in DIR/series.csv (column body_mean_vz).
double terminal_speed(const std::string& dir) {
  std::ifstream in(dir + "/series.csv");
  std::string line;
  std::getline(in, line);
  int column = -1, k = 0;
  std::stringstream header(line);
  for (std::string name; std::getline(header, name, ','); ++k)
    if (name == "body_mean_vz") column = k;
  double fastest = 0;
  while (std::getline(in, line)) {
    std::stringstream row(line);
    std::string cell;
    for (int c = 0; std::getline(row, cell, ','); ++c)
      if (c == column && !cell.empty()) fastest = std::max(fastest, -std::stod(cell));
  }
  return fastest;
}

}  // namespace

TEST(SettlingSphere, TenCateE3TerminalSpeed) {
  const double measured = 0.091;
  for (const char* cells : {"[28,28,44]", "[56,56,88]"}) {
    const std::string dir = std::string("settling_out/") + cells;
    test::run_case_on(test::world_size(), case_text(),
                      {std::string("fluid.cells=") + cells, "output.snapshot_interval=0", "output.progress_interval=1000"},
                      dir);
    if (test::world_rank() != 0) continue;
    const double u = terminal_speed(dir), err = std::abs(u - measured) / measured;
    std::printf("  cells %s: terminal speed %.4f m/s, measured %.3f m/s, error %.1f %%\n", cells, u, measured,
                100 * err);
    EXPECT_LT(err, 0.07);
  }
}
