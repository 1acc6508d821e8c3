// SPDX-License-Identifier: MIT
// What each rank of a Cartesian process grid would do in a DEM step, counted on one process from
// the bodies' positions (issue 19: the scaling model's per-rank work, without running P ranks).
//
// The counts follow the ownership rule of halo.hpp: a rank owns the bodies whose centres its
// sub-box holds; it evaluates every listed pair with at least one owned body (a pair across a cut is
// evaluated on both sides); its ghosts are the bodies within r + r_max + skin of a face, swept x,
// y, z with forwarding, so a ghost crosses at most one face per direction (slabs are at least the
// reach wide). A pair is listed when the centres are closer than r_a + r_b + skin (neighbor_list).
#pragma once
#include <array>
#include <vector>

#include "core/balance.hpp"
#include "core/vec3.hpp"

namespace tessera {

struct RankLoad {
  std::vector<double> bodies;  // owned bodies per rank (rank order: x fastest)
  std::vector<double> pairs;   // listed pairs each rank evaluates
  std::vector<double> ghosts;  // ghost copies each rank holds
  // Bodies each rank lays out over its cells (a coupled run's solid fraction, SolidPhase::update):
  // its owned bodies and the ghosts whose farthest node reaches its sub-box, open at the domain's
  // sides (the wall cells take what lies beyond them). Empty unless the nodes' reach is given.
  std::vector<double> laid_out;
  // Ghosts each rank receives in each of the six swaps (direction d, from the low / high side):
  // recv[rank][2 d + side]. A swap moves them every step (x, v, omega).
  std::vector<std::array<double, 6>> recv;
  // Shaped bodies' contact spheres, when their places are given: each rank's owned elements and the
  // ghosts' elements its list bins (those within the margin of its faces with a neighbour, theory
  // T5b; DemSolver's listed_elements() is their sum at a whole list).
  std::vector<double> owned_elements, listed_ghost_elements;
  // And the elements a whole listing's searches meet on each rank (NeighborList::tests: the list's
  // work, theory T5c), from that rank's list made here; when the elements' radii are given.
  std::vector<double> list_tests;
  double total_pairs = 0;  // distinct listed pairs
};

// Each body's listed pairs (the pairs it takes part in): 1 plus this is the work per body that a
// run's load balance counts (DemSolver::work).
std::vector<double> listed_pairs_per_body(const std::vector<Vec3>& x, const std::vector<double>& radius, double skin);

// Each body's contact spheres in the world frame: body b's are x[first[b]] .. x[first[b + 1] - 1];
// margin: R_max + r_max + 3 s (theory T5b).
struct ElementPlaces {
  std::vector<Vec3> x;
  std::vector<std::size_t> first;
  double margin = 0;
  std::vector<double> radius;  // per element; empty: the ranks' lists are not made (no list_tests)
};

// x: body centres, radius: their radii; dims and interior cuts as Decomposition's; skin the
// neighbour list's; node_reach: each body's farthest tetrahedron node from its centre (a coupled
// run's bodies), or empty; elements: the bodies' contact spheres, or null.
RankLoad dem_rank_load(const std::vector<Vec3>& x, const std::vector<double>& radius, const Vec3& lo, const Vec3& hi,
                       std::array<int, 3> dims, const CutPlanes& interior, double skin,
                       const std::vector<double>& node_reach = {}, const ElementPlaces* elements = nullptr);

}  // namespace tessera
