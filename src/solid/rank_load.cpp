// SPDX-License-Identifier: MIT
#include "solid/rank_load.hpp"

#include <algorithm>
#include <cstdint>

#include "solid/neighbor_list.hpp"

namespace tessera {

namespace {

// The run's list made over these elements (3 coordinates each, unit masses; body empty: element i
// is body i), the first `owned` of them owned.
NeighborList made_list(const std::vector<double>& flat, const std::vector<double>& radius,
                       const std::vector<std::int64_t>& key, const std::vector<std::int32_t>& body, std::size_t owned,
                       double skin) {
  const std::vector<double> mass(body.empty() ? radius.size() : static_cast<std::size_t>(body.back()) + 1, 1.0);
  ContactElements e;
  e.size = radius.size();
  e.owned = owned;
  e.x = flat.data();
  e.radius = radius.data();
  e.key = key.data();
  e.body = body.empty() ? nullptr : body.data();
  e.body_mass = mass.data();
  NeighborList list;
  list.build(e, skin, {});
  return list;
}

// Every pair the run's neighbour list would list (closer than r_a + r_b + skin): the list itself,
// built over all bodies as if one rank owned them.
template <class F>
void for_each_listed_pair(const std::vector<Vec3>& x, const std::vector<double>& radius, double skin, F&& f) {
  if (x.empty()) return;
  std::vector<double> flat(3 * x.size());
  std::vector<std::int64_t> key(x.size());
  for (std::size_t a = 0; a < x.size(); ++a) {
    for (int d = 0; d < 3; ++d) flat[3 * a + static_cast<std::size_t>(d)] = x[a][d];
    key[a] = static_cast<std::int64_t>(a);
  }
  const NeighborList list = made_list(flat, radius, key, {}, x.size(), skin);
  for (std::size_t k = 0; k < list.size(); ++k)
    f(static_cast<std::size_t>(list.first[k]), static_cast<std::size_t>(list.second[k]));
}

// The elements one rank's whole listing meets (NeighborList::tests): its owned bodies' elements
// first, then the listed ghosts' (each body's elements consecutive, as the DEM stores them), keyed
// by their global index.
double rank_list_tests(const ElementPlaces& el, const std::vector<std::size_t>& owned_bodies,
                       const std::vector<std::pair<std::size_t, std::size_t>>& ghost_elements, double skin) {
  std::vector<double> flat, radius;
  std::vector<std::int64_t> key;
  std::vector<std::int32_t> body;
  auto add = [&](std::size_t e, std::int32_t b) {
    for (int d = 0; d < 3; ++d) flat.push_back(el.x[e][d]);
    radius.push_back(el.radius[e]);
    key.push_back(static_cast<std::int64_t>(e));
    body.push_back(b);
  };
  std::int32_t local = 0;  // local body index
  for (const std::size_t a : owned_bodies) {
    for (std::size_t e = el.first[a]; e < el.first[a + 1]; ++e) add(e, local);
    ++local;
  }
  const std::size_t owned = radius.size();
  for (std::size_t k = 0; k < ghost_elements.size(); ++k) {  // grouped by body
    if (k > 0 && ghost_elements[k].first != ghost_elements[k - 1].first) ++local;
    add(ghost_elements[k].second, local);
  }
  if (radius.empty()) return 0.0;
  return static_cast<double>(made_list(flat, radius, key, body, owned, skin).tests);
}

}  // namespace

std::vector<double> listed_pairs_per_body(const std::vector<Vec3>& x, const std::vector<double>& radius, double skin) {
  std::vector<double> n(x.size(), 0.0);
  for_each_listed_pair(x, radius, skin, [&](std::size_t a, std::size_t b) { n[a] += 1, n[b] += 1; });
  return n;
}

RankLoad dem_rank_load(const std::vector<Vec3>& x, const std::vector<double>& radius, const Vec3& lo, const Vec3& hi,
                       std::array<int, 3> dims, const CutPlanes& interior, double skin,
                       const std::vector<double>& node_reach, const ElementPlaces* elements) {
  const std::size_t ranks = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
  RankLoad load;
  load.bodies.assign(ranks, 0.0);
  load.pairs.assign(ranks, 0.0);
  load.ghosts.assign(ranks, 0.0);
  load.recv.assign(ranks, {});
  const bool lays_out = !node_reach.empty();
  if (lays_out) load.laid_out.assign(ranks, 0.0);
  if (elements) load.owned_elements.assign(ranks, 0.0), load.listed_ghost_elements.assign(ranks, 0.0);
  if (x.empty()) return load;
  // Each rank's owned bodies and listed ghost elements (body, element), for its list's work.
  const bool lists = elements && elements->radius.size() == elements->x.size();
  std::vector<std::vector<std::size_t>> owned_bodies(lists ? ranks : 0);
  std::vector<std::vector<std::pair<std::size_t, std::size_t>>> ghost_elements(lists ? ranks : 0);
  std::array<std::vector<double>, 3> planes;  // dims[d] + 1 planes per direction
  for (int d = 0; d < 3; ++d) {
    planes[d].push_back(lo[d]);
    for (const double c : interior[d]) planes[d].push_back(c);
    planes[d].push_back(hi[d]);
  }
  auto rank_of = [&](const std::array<int, 3>& c) {
    return static_cast<std::size_t>(c[0] + dims[0] * (c[1] + dims[1] * c[2]));
  };
  const double r_max = *std::max_element(radius.begin(), radius.end());
  std::vector<std::size_t> owner(x.size());
  for (std::size_t a = 0; a < x.size(); ++a) {
    std::array<int, 3> c{};
    const int g = grid_cell(x[a], dims, interior);
    c[0] = g % dims[0], c[1] = (g / dims[0]) % dims[1], c[2] = g / (dims[0] * dims[1]);
    owner[a] = static_cast<std::size_t>(g);
    load.bodies[owner[a]] += 1;
    if (lays_out) load.laid_out[owner[a]] += 1;
    if (elements) load.owned_elements[owner[a]] += static_cast<double>(elements->first[a + 1] - elements->first[a]);
    if (lists) owned_bodies[owner[a]].push_back(a);
    // Ghosts: per direction, the slab itself or a neighbour across a face within the reach; every
    // combination but the body's own cell is a rank holding a copy.
    const double reach = radius[a] + r_max + skin;
    std::array<std::vector<int>, 3> options;
    for (int d = 0; d < 3; ++d) {
      options[d].push_back(c[d]);
      if (c[d] > 0 && x[a][d] - planes[d][static_cast<std::size_t>(c[d])] < reach) options[d].push_back(c[d] - 1);
      if (c[d] + 1 < dims[d] && planes[d][static_cast<std::size_t>(c[d]) + 1] - x[a][d] < reach)
        options[d].push_back(c[d] + 1);
    }
    for (const int i : options[0])
      for (const int j : options[1])
        for (const int k : options[2]) {
          const std::array<int, 3> t{i, j, k};
          if (t == c) continue;
          const std::size_t r = rank_of(t);
          load.ghosts[r] += 1;
          if (lays_out) {  // does a node reach the rank's sub-box (open where it meets the domain's side)?
            double d2 = 0;
            for (int d = 0; d < 3; ++d) {
              const auto i = static_cast<std::size_t>(t[d]);
              const double below = t[d] > 0 ? planes[d][i] - x[a][d] : 0.0;
              const double above = t[d] + 1 < dims[d] ? x[a][d] - planes[d][i + 1] : 0.0;
              const double out = std::max({below, above, 0.0});
              d2 += out * out;
            }
            if (d2 <= node_reach[a] * node_reach[a]) load.laid_out[r] += 1;
          }
          if (elements) {  // its elements within the margin of the rank's faces with a neighbour
            for (std::size_t e = elements->first[a]; e < elements->first[a + 1]; ++e) {
              bool near = true;
              for (int d = 0; d < 3 && near; ++d) {
                const auto i = static_cast<std::size_t>(t[d]);
                if (t[d] > 0 && elements->x[e][d] < planes[d][i] - elements->margin) near = false;
                if (t[d] + 1 < dims[d] && elements->x[e][d] > planes[d][i + 1] + elements->margin) near = false;
              }
              load.listed_ghost_elements[r] += near;
              if (lists && near) ghost_elements[r].emplace_back(a, e);
            }
          }
          // It arrives in the last direction in which it moves (x, then y, then z).
          for (int d = 2; d >= 0; --d)
            if (t[d] != c[d]) {
              load.recv[r][static_cast<std::size_t>(2 * d + (t[d] < c[d] ? 1 : 0))] += 1;
              break;
            }
        }
  }
  for_each_listed_pair(x, radius, skin, [&](std::size_t a, std::size_t b) {
    load.total_pairs += 1;
    load.pairs[owner[a]] += 1;
    if (owner[b] != owner[a]) load.pairs[owner[b]] += 1;
  });
  if (lists) {
    load.list_tests.assign(ranks, 0.0);
    for (std::size_t r = 0; r < ranks; ++r) {
      load.list_tests[r] = rank_list_tests(*elements, owned_bodies[r], ghost_elements[r], skin);
      std::vector<std::size_t>().swap(owned_bodies[r]);
      std::vector<std::pair<std::size_t, std::size_t>>().swap(ghost_elements[r]);
    }
  }
  return load;
}

}  // namespace tessera
