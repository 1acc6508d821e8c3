// SPDX-License-Identifier: MIT
// A sphere settling in a viscous liquid against ten Cate et al. (2002, Phys. Fluids 14, 4012), case
// E3: a 15 mm nylon sphere (1120 kg/m^3) in silicone oil (962 kg/m^3, 0.113 Pa s) in a closed box of
// 100 x 100 mm cross-section, measured terminal speed 0.091 m/s (Re 11.6). The shipped case
// (cases/coupled/settling_sphere.yaml: the experiment's 160 mm box and 0.8 s) on a box twice as tall
// (320 mm, the sphere starting 40 mm below the top as in the experiment) and to 1.5 s: in the
// experiment's box the sphere is still rising at 0.8 s (2 % below the speed it ends at on 4.2 cells
// per diameter, 2026-11-30), and the measurement is the terminal speed. On 4.2 and 8.4 cells per
// diameter the terminal speed must come within 3 % of the measurement (measured 2026-11-30: -0.4 %
// and -2.7 %). The error grows with the grid, which is open (issue 15, docs/validation.md); 3 % is
// the 8.4-cell grid's error with the margin of the last 0.06 % the sphere was still rising by.
// For scale: Schiller-Naumann's drag gives 0.093 m/s unbounded.
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

// The terminal speed on nx x nx x nz cells (nx across the 100 mm box) in the 320 mm box.
void check_terminal_speed(int nx, int nz) {
  const double measured = 0.091;
  const std::string cells = "[" + std::to_string(nx) + "," + std::to_string(nx) + "," + std::to_string(nz) + "]";
  const std::string dir = "settling_out/tall_" + std::to_string(nx);
  const std::string top = "[50 mm, 50 mm, 320 mm]";
  test::run_case_on(test::world_size(), case_text(),
                    {"fluid.cells=" + cells, "domain.box_max=" + top, "solid.walls.0.max=" + top,
                     "initial.liquid.0.box.max=" + top, "bodies.list.0.position=[0, 0, 280 mm]", "run.end_time=1.5 s",
                     "output.snapshot_interval=0", "output.progress_interval=1000"},
                    dir);
  if (test::world_rank() != 0) return;
  const double u = terminal_speed(dir), err = (u - measured) / measured;
  std::printf("  cells %s (%.1f per diameter): terminal speed %.4f m/s, measured %.3f m/s, error %+.1f %%\n",
              cells.c_str(), 15.0 * nx / 100.0, u, measured, 100 * err);
  EXPECT_LT(std::abs(err), 0.03);
}

TEST(SettlingSphere, TenCateE3TerminalSpeed) {
  check_terminal_speed(28, 88);   // 4.2 cells per diameter, 25 s on 2 ranks
  check_terminal_speed(56, 176);  // 8.4, 3.5 minutes
}
