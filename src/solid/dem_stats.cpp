// SPDX-License-Identifier: MIT
// DemSolver::stats(): energies (exact sums), speeds, contacts (elements and bodies, across ranks),
// overlaps and finiteness, for the run loop's health checks, settle criteria and summary.json.
#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "core/exact_sum.hpp"
#include "solid/dem_solver.hpp"

namespace tessera {

DemStats DemSolver::stats() const {
  if (kick_pending_) throw std::logic_error("DemSolver::stats: a deferred half-kick is pending (complete_step)");
  // Energies as exact sums (core/exact_sum.hpp): the same bits on any rank count.
  ExactSum energy[2];
  double e[3] = {0, 0, 0};
  // bodies, contacts, wall contacts, non-finite, body pairs, contacts with a ghost
  long c[6] = {static_cast<long>(p_.owned), 0, 0, 0, 0, 0};
  struct {
    double ratio;
    int body;
  } worst{0.0, -1};
  auto note_overlap = [&](double overlap, double radius, std::int64_t id) {
    if (overlap / radius > worst.ratio) worst = {overlap / radius, static_cast<int>(id)};
  };
  for (std::size_t i = 0; i < p_.owned; ++i) {
    const Vec3 x = p_.pos(i), v = p_.vel(i), w = p_.ang(i);
    if (!std::isfinite(norm2(x) + norm2(v) + norm2(w))) ++c[3];
    energy[0] += 0.5 * p_.mass[i] * norm2(v);
    if (anisotropic(p_.shape[i])) {
      const Quaternion q{p_.q[4 * i], p_.q[4 * i + 1], p_.q[4 * i + 2], p_.q[4 * i + 3]};
      const Vec3 wb = q.unrotate(w);
      double rotational = 0;
      for (int k = 0; k < 3; ++k) rotational += 0.5 * inertia3_[3 * i + k] * wb[k] * wb[k];
      energy[1] += rotational;
    } else {
      energy[1] += 0.5 * p_.inertia[i] * norm2(w);
    }
    e[2] = std::max(e[2], norm(v));
  }
  // Contacts between elements (bodies for spheres): positions and radii of elements.
  const bool sh = shaped();
  // Elements where their bodies are now (between lists only the listed ones are placed a step).
  auto ex = [&](std::size_t a) { return entities_.position(shapes_, a); };
  auto er = [&](std::size_t a) { return entities_.radius(a); };
  auto eid = [&](std::size_t a) { return p_.id[entities_.body(a)]; };
  const std::size_t owned_elements = entities_.owned();
  std::unordered_set<PairKey> touching_bodies;
  for (std::size_t k = 0; k < pairs_.list().size(); ++k) {
    const auto a = static_cast<std::size_t>(pairs_.list().first[k]), b = static_cast<std::size_t>(pairs_.list().second[k]);
    if (a >= owned_elements) continue;  // counted by the owner of the lower-key element
    const double r = norm(ex(a) - ex(b)), rs = er(a) + er(b);
    if (r < rs) {
      ++c[1];
      if (b >= owned_elements) ++c[5];
      note_overlap(rs - r, std::min(er(a), er(b)), eid(a));
      // Body pairs: a body's element keys all precede a higher-order body's, so the lower element's
      // body is the pair's lower body and its owner counts the pair.
      if (sh) touching_bodies.insert(pair_key(p_.order[entities_.body(a)], p_.order[entities_.body(b)]));
    }
  }
  c[4] = sh ? static_cast<long>(touching_bodies.size()) : c[1];
  for (std::size_t i = 0; i < owned_elements; ++i)
    for (const auto& w : walls_.primitives()) {
      Vec3 n;
      const double overlap = w.overlap(ex(i), er(i), n);
      if (overlap > 0) {
        ++c[2];
        note_overlap(overlap, er(i), eid(i));
      }
    }
  MPI_Comm comm = decomp_.comm();
  // Free spheres are held on every rank: added once, after the sums.
  ExactSum::all_reduce(energy, comm);
  for (const FreeSphere& fs : free_.spheres()) {
    energy[0] += 0.5 * fs.mass * norm2(fs.v);
    energy[1] += 0.5 * fs.inertia * norm2(fs.omega);
  }
  e[0] = energy[0].value(), e[1] = energy[1].value();
  MPI_Allreduce(MPI_IN_PLACE, &e[2], 1, MPI_DOUBLE, MPI_MAX, comm);
  MPI_Allreduce(MPI_IN_PLACE, c, 6, MPI_LONG, MPI_SUM, comm);
  if (!std::isfinite(worst.ratio)) worst.ratio = 1e300;
  MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_DOUBLE_INT, MPI_MAXLOC, comm);
  for (const FreeSphere& fs : free_.spheres()) {
    if (!std::isfinite(norm2(fs.x) + norm2(fs.v) + norm2(fs.omega))) ++c[3];
    e[2] = std::max(e[2], norm(fs.v));
  }
  DemStats s;
  s.bodies = c[0];
  s.contacts = c[1];
  s.body_contacts = c[4];
  s.wall_contacts = c[2];
  s.cross_rank_contacts = c[5];
  s.finite = c[3] == 0;
  s.kinetic_translational = e[0];
  s.kinetic_rotational = e[1];
  s.max_speed = e[2];
  s.max_overlap_ratio = worst.ratio;
  s.max_overlap_body = worst.body;
  return s;
}

}  // namespace tessera
