// SPDX-License-Identifier: MIT
#include "solid/pair_contacts.hpp"

#include <algorithm>

#include "solid/disc_overlaps.hpp"
#include "solid/touching_pass.hpp"

namespace tessera {

void PairContacts::start_list() {
  was_touching_.resize(list_.size());
  for (std::size_t k = 0; k < list_.size(); ++k)
    was_touching_[k] =
        list_.history[3 * k] != 0.0 || list_.history[3 * k + 1] != 0.0 || list_.history[3 * k + 2] != 0.0;
}

void PairContacts::fill_materials(const ContactEntities& entities, const ContactModel& model) {
  // The law's per-pair coefficients (five doubles) are not stored: the kernel makes them from the
  // material pair's parameters, m* (listed) and R* (the lanes' radii), which streams 12 bytes a
  // contact instead of 44 and leaves nothing to fill at a list build but this index.
  material_pair_.resize(list_.size());
  const int nm = model.material_count();
  for (std::size_t k = 0; k < list_.size(); ++k)
    material_pair_[k] = entities.material(list_.first[k]) * nm + entities.material(list_.second[k]);
}

// The pair loop's access to one mirror layout: packing a body's mirror, pass 1's overlap test, the
// partner's prefetches, the gather of a pair into a lane and the accumulation of its force.
struct PairContacts::SphereMirrors {  // 3D mirrors per element (spheres, shaped bodies' elements)
  const ParticleStore& p;
  const ContactEntities& entities;
  KernelGeometry* g;
  KernelMotion* m;
  KernelForce* out;
  bool sh;
  void pack(std::size_t i) {
    const double* x = &p.x[3 * i];
    const double* v = &p.v[3 * i];
    const double* w = &p.omega[3 * i];
    g[i] = {x[0], x[1], x[2], p.radius[i]};
    m[i] = {v[0], v[1], v[2], w[0], w[1], w[2]};
  }
  // Pass 1: the scalar loop (touching_pass.hpp) with the sphere test.
  std::size_t find_touching(const std::int32_t* first, const std::int32_t* second, std::size_t np,
                            std::int32_t* out, std::uint8_t* was, double* hist) const {
    return find_touching_scalar(g, first, second, 0, np, 0, out, was, hist,
                                [](const KernelGeometry& ga, const KernelGeometry& gb) {
                                  const double dx = ga.x - gb.x, dy = ga.y - gb.y, dz = ga.z - gb.z;
                                  const double rsum = ga.r + gb.r;
                                  return dx * dx + dy * dy + dz * dz < rsum * rsum;
                                });
  }
  void prefetch_partner(std::size_t b) const {
    __builtin_prefetch(&g[b]);
    __builtin_prefetch(&m[b]);
    __builtin_prefetch(&out[b], 1);
  }
  void gather(ContactLanes& L, std::size_t j, std::size_t a, std::size_t b) const {
    const KernelGeometry &ga = g[a], &gb = g[b];
    const KernelMotion &ma = m[a], &mb = m[b];
    L.dx[j] = ga.x - gb.x, L.dy[j] = ga.y - gb.y, L.dz[j] = ga.z - gb.z;
    L.ra[j] = ga.r, L.rb[j] = gb.r;
    L.vx[j] = ma.vx - mb.vx, L.vy[j] = ma.vy - mb.vy, L.vz[j] = ma.vz - mb.vz;
    L.wx[j] = ma.wx * ga.r + mb.wx * gb.r;
    L.wy[j] = ma.wy * ga.r + mb.wy * gb.r;
    L.wz[j] = ma.wz * ga.r + mb.wz * gb.r;
  }
  void evaluate(LawKind law, ContactLanes& L, std::size_t count, double dt, const PairParams* params) const {
    evaluate_contacts(law, L, count, dt, params);
  }
  void accumulate(const ContactLanes& L, std::size_t j, std::size_t ea, std::size_t eb) {
    const std::size_t a = sh ? entities.body(ea) : ea;
    const std::size_t b = sh ? entities.body(eb) : eb;
    KernelForce &fa = out[a], &fb = out[b];
    fa.fx += L.fx[j], fa.fy += L.fy[j], fa.fz += L.fz[j];
    fb.fx -= L.fx[j], fb.fy -= L.fy[j], fb.fz -= L.fz[j];
    fa.tx -= L.nx[j] * L.ra[j], fa.ty -= L.ny[j] * L.ra[j], fa.tz -= L.nz[j] * L.ra[j];
    fb.tx -= L.nx[j] * L.rb[j], fb.ty -= L.ny[j] * L.rb[j], fb.tz -= L.nz[j] * L.rb[j];
    if (sh) {
      entities.add_lever(fa, g[ea], a, L.fx[j], L.fy[j], L.fz[j]);
      entities.add_lever(fb, g[eb], b, -L.fx[j], -L.fy[j], -L.fz[j]);
    }
  }
};

template <int N>
struct PairContacts::DiscMirrors {  // plane mode, normal along axis N (kernel_mirrors.hpp)
  static constexpr int U = plane_u(N), V = plane_v(N);
  const ParticleStore& p;
  DiscMirror* g;
  DiscForce* out;
  void pack(std::size_t i) {
    const double* x = &p.x[3 * i];
    const double* v = &p.v[3 * i];
    g[i] = {x[U], x[V], p.radius[i], v[U], v[V], p.omega[3 * i + N]};
  }
  // Pass 1: vectorised (disc_overlaps.hpp).
  std::size_t find_touching(const std::int32_t* first, const std::int32_t* second, std::size_t np,
                            std::int32_t* out, std::uint8_t* was, double* hist) const {
    return find_disc_overlaps({g, first, second, np, out, was, hist});
  }
  void prefetch_partner(std::size_t b) const {
    __builtin_prefetch(&g[b]);
    __builtin_prefetch(&out[b], 1);
  }
  // The in-plane lanes only (the disc kernel reads no others) and the spring's three components
  // (the pair loop stores three back: the normal one stays as listed, zero).
  void gather(ContactLanes& L, std::size_t j, std::size_t a, std::size_t b) const {
    const DiscMirror &ga = g[a], &gb = g[b];
    double* d[3] = {L.dx, L.dy, L.dz};
    double* v[3] = {L.vx, L.vy, L.vz};
    d[U][j] = ga.u - gb.u, d[V][j] = ga.v - gb.v;
    L.ra[j] = ga.r, L.rb[j] = gb.r;
    v[U][j] = ga.vu - gb.vu, v[V][j] = ga.vv - gb.vv;
    double* w[3] = {L.wx, L.wy, L.wz};
    w[N][j] = ga.wn * ga.r + gb.wn * gb.r;
  }
  void evaluate(LawKind law, ContactLanes& L, std::size_t count, double dt, const PairParams* params) const {
    evaluate_disc_contacts(law, N, L, count, dt, params);
  }
  void accumulate(const ContactLanes& L, std::size_t j, std::size_t a, std::size_t b) {
    const double* f[3] = {L.fx, L.fy, L.fz};
    const double* nf[3] = {L.nx, L.ny, L.nz};
    DiscForce &fa = out[a], &fb = out[b];
    fa.fu += f[U][j], fa.fv += f[V][j];
    fb.fu -= f[U][j], fb.fv -= f[V][j];
    fa.tn -= nf[N][j] * L.ra[j];
    fb.tn -= nf[N][j] * L.rb[j];
  }
};

void PairContacts::forces(ContactEntities& entities, std::size_t packed, ContactLanes& lanes,
                          const ContactModel& model, double dt, bool update_history) {
  entities.start_forces();
  const ParticleStore& p = entities.bodies();
  if (!entities.discs()) {
    SphereMirrors view{p, entities, entities.geometry_mirrors().data(), entities.motion_mirrors().data(),
                       entities.forces().data(), entities.shaped()};
    loop(view, entities, packed, lanes, model, dt, update_history);
    return;
  }
  DiscMirror* g = entities.disc_mirrors().data();
  DiscForce* f = entities.disc_forces().data();
  auto run = [&](auto view) { loop(view, entities, packed, lanes, model, dt, update_history); };
  switch (entities.plane_normal()) {
    case 0: run(DiscMirrors<0>{p, g, f}); break;
    case 1: run(DiscMirrors<1>{p, g, f}); break;
    default: run(DiscMirrors<2>{p, g, f}); break;
  }
}

template <class Mirrors>
void PairContacts::loop(Mirrors& view, ContactEntities& entities, std::size_t packed, ContactLanes& L,
                        const ContactModel& model, double dt, bool update_history) {
  const std::size_t n = entities.size();
  const std::size_t np = list_.size();
  const std::int32_t* first = list_.first.data();
  const std::int32_t* second = list_.second.data();
  double* hist = list_.history.data();
  // Owned bodies were packed by the integrator unless a rebuild moved them; ghosts always here.
  // (Shaped mode: every element was placed by ContactEntities::place.)
  for (std::size_t i = packed; i < n; ++i) view.pack(i);
  // Pass 1: which listed pairs touch, in list order (the view's find_touching).
  // touching_ keeps its size (a shrink and a regrow would zero-fill it at every evaluation): its
  // first nt entries are this evaluation's.
  if (touching_.size() < np + 8) touching_.resize(np + 8);
  was_touching_.resize(np, 0);
  const std::size_t nt = view.find_touching(first, second, np, touching_.data(),
                                            update_history ? was_touching_.data() : nullptr, hist);
  constexpr std::size_t ahead = 16;  // pass 2's prefetch distance
  if (entities.shaped())
    for (std::size_t t = 0; t < nt; ++t) {
      entities.refresh_motion(first[touching_[t]]);
      entities.refresh_motion(second[touching_[t]]);
    }
  // Pass 2, in blocks: gather the pairs' data into lanes, evaluate the law on all lanes
  // (vectorised, contact_kernel.cpp), then accumulate forces in canonical order.
  constexpr std::size_t B = ContactLanes::width;
  const std::int32_t* pm = material_pair_.data();
  const double* meff = list_.meff.data();
  const PairParams* params = model.pair_table();
  const LawKind law = model.law();
  for (std::size_t s = 0; s < nt; s += B) {
    const std::size_t nb = std::min(B, nt - s);
    for (std::size_t j = 0; j < nb; ++j) {
      if (s + j + ahead < nt) {
        // The partner's lines (pass 1 read its geometry long ago: a large bed's mirrors leave the
        // cache in between) and the pair's history.
        const std::size_t kk = static_cast<std::size_t>(touching_[s + j + ahead]);
        view.prefetch_partner(second[kk]);
        __builtin_prefetch(&hist[3 * kk], 1);
      }
      const std::size_t k = static_cast<std::size_t>(touching_[s + j]);
      view.gather(L, j, first[k], second[k]);
      L.hx[j] = hist[3 * k], L.hy[j] = hist[3 * k + 1], L.hz[j] = hist[3 * k + 2];
      L.meff[j] = meff[k], L.pair[j] = pm[k];
    }
    view.evaluate(law, L, nb, dt, params);
    for (std::size_t j = 0; j < nb; ++j) {
      const std::size_t k = static_cast<std::size_t>(touching_[s + j]);
      hist[3 * k] = L.hx[j], hist[3 * k + 1] = L.hy[j], hist[3 * k + 2] = L.hz[j];
      view.accumulate(L, j, first[k], second[k]);
    }
  }
}

}  // namespace tessera
