// SPDX-License-Identifier: MIT
#include "fluid/flow_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/errors.hpp"
#include "core/exact_sum.hpp"
#include "fluid/flow_cells.hpp"
#include "fluid/plic.hpp"

namespace tessera {

using flow_cells::face_viscosity;
using flow_cells::for_box;
using flow_cells::for_wall_layers;
using flow_cells::kEmpty;
using flow_cells::kFull;

FlowSolver::FlowSolver(const Decomposition& decomp, const FlowSettings& settings) : settings_(settings) {
  grid_ = std::make_unique<FluidGrid>(decomp, settings.cells, settings.boundaries);
  poisson_ = std::make_unique<PressurePoisson>(*grid_, settings.poisson);
  make_fields();
}

void FlowSolver::repartition(const Decomposition& decomp) {
  timers();  // the old grid's and multigrid's exchange seconds into the timers
  multigrid_carried_ += poisson_->halo_traffic();
  poisson_.reset();
  grid_->repartition(decomp);
  fields_reported_ = grid_->exchange_seconds(), multigrid_reported_ = 0;
  poisson_ = std::make_unique<PressurePoisson>(*grid_, settings_.poisson);
  make_fields();
  keep_advection_change(!advection_change_[0].empty());
  keep_stress_divergence(!stress_div_[0].empty());
  interface_phi_.clear();
  drag_density_.clear();
  drag_ = nullptr;
}

void FlowSolver::make_fields() {
  const FluidGrid& g = *grid_;
  f_ = g.make_field();
  p_ = g.make_field();
  rho_ = g.make_field();
  mu_ = g.make_field();
  indicator_ = g.make_field();
  dilatation_ = g.make_field();
  upwind_cell_ = g.make_field();
  rhs_ = g.make_field();
  flux_f_ = g.make_field();
  flux_m_ = g.make_field();
  sweep_f_ = g.make_field();
  for (int d = 0; d < 3; ++d) {
    u_[d] = g.make_field();
    sweep_u_[d] = g.make_field();
    uf_[d] = g.make_field();
    work_[d] = g.make_field();
    face_accel_[d] = g.make_field();
    flux_q_[d] = g.make_field();
  }
  for (auto& a : plic_) a = g.make_field();
  if (settings_.energy_budget) advection_source_ = g.make_field();
}

FlowSolver::~FlowSolver() = default;

void FlowSolver::initialize(const std::function<CellState(int, int, int)>& cell) {
  const FluidGrid& g = *grid_;
  for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)}, [&](int i, int j, int k) {
    const CellState s = cell(i, j, k);
    const std::size_t c = g.at(i, j, k);
    f_[c] = s.liquid_fraction;
    for (int d = 0; d < 3; ++d) u_[d][c] = s.velocity[d];
  });
  refresh();
  project(1.0, false);  // divergence-free face velocities for the first step
  std::fill(p_.begin(), p_.end(), 0.0);
}

void FlowSolver::velocity_changed() {
  grid_->exchange({&u_[0], &u_[1], &u_[2]});
  fill_velocity_ghosts(u_);
}

void FlowSolver::fraction_changed() {
  grid_->exchange(f_);
  fill_fraction_ghosts(f_);
  update_properties();
}

void FlowSolver::keep_advection_change(bool on) {
  for (auto& a : advection_change_) a = on ? grid_->make_field() : std::vector<double>{};
}

void FlowSolver::keep_stress_divergence(bool on) {
  for (auto& s : stress_div_) s = on ? grid_->make_field() : std::vector<double>{};
}

void FlowSolver::refresh() {
  grid_->exchange({&f_, &u_[0], &u_[1], &u_[2], &p_, &uf_[0], &uf_[1], &uf_[2]});
  fill_fraction_ghosts(f_);
  fill_velocity_ghosts(u_);
  fill_pressure_ghosts();
  update_properties();
}

// ---------------------------------------------------------------------------------------------
// Boundary ghosts. Layer g (1, 2) beyond a non-periodic side mirrors interior layer g - 1.
namespace {

template <class F>
void for_boundary_ghosts(const FluidGrid& g, int d, int side, F&& fn) {
  std::array<int, 3> lo{g.gbegin(0), g.gbegin(1), g.gbegin(2)}, hi{g.gend(0), g.gend(1), g.gend(2)};
  const int n = g.cells()[d];
  for (int layer = 1; layer <= FluidGrid::kGhost; ++layer) {
    const int ghost = side == 0 ? -layer : n - 1 + layer;
    const int mirror = side == 0 ? layer - 1 : n - layer;
    std::array<int, 3> a = lo, b = hi;
    a[d] = ghost;
    b[d] = ghost + 1;
    for_box(a, b, [&](int i, int j, int k) {
      std::array<int, 3> m{i, j, k};
      m[d] = mirror;
      fn(g.at(i, j, k), g.at(m[0], m[1], m[2]));
    });
  }
}

}  // namespace

void FlowSolver::fill_fraction_ghosts(std::vector<double>& f) const {
  const FluidGrid& g = *grid_;
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side)
      if (g.at_domain_edge(d, side))
        for_boundary_ghosts(g, d, side, [&](std::size_t gh, std::size_t in) { f[gh] = f[in]; });
}

void FlowSolver::fill_velocity_ghosts(std::array<std::vector<double>, 3>& u) const {
  const FluidGrid& g = *grid_;
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      if (!g.at_domain_edge(d, side)) continue;
      const BoundaryKind kind = g.boundary(d, side);
      for (int q = 0; q < 3; ++q) {
        // no-slip: the wall is at rest, every component odd; free-slip: the normal one odd;
        // outflow: zero gradient.
        const bool odd = kind == BoundaryKind::no_slip || (kind == BoundaryKind::free_slip && q == d);
        auto& uq = u[q];
        if (odd)
          for_boundary_ghosts(g, d, side, [&](std::size_t gh, std::size_t in) { uq[gh] = -uq[in]; });
        else
          for_boundary_ghosts(g, d, side, [&](std::size_t gh, std::size_t in) { uq[gh] = uq[in]; });
      }
    }
}

void FlowSolver::fill_pressure_ghosts() {
  const FluidGrid& g = *grid_;
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      if (!g.at_domain_edge(d, side)) continue;
      if (g.boundary(d, side) == BoundaryKind::outflow)
        for_boundary_ghosts(g, d, side, [&](std::size_t gh, std::size_t in) { p_[gh] = -p_[in]; });
      else
        for_boundary_ghosts(g, d, side, [&](std::size_t gh, std::size_t in) { p_[gh] = p_[in]; });
    }
}

void FlowSolver::update_properties() {
  const double rg = settings_.gas.density, dr = settings_.liquid.density - rg;
  const double mg = settings_.gas.viscosity, dm = settings_.liquid.viscosity - mg;
  for (std::size_t c = 0; c < f_.size(); ++c) {
    rho_[c] = rg + dr * f_[c];
    mu_[c] = mg + dm * f_[c];
  }
}

// ---------------------------------------------------------------------------------------------
// Time step control.
double FlowSolver::stable_dt(std::string& limit) const {
  const FluidGrid& g = *grid_;
  double rate = 0;
  for (int d = 0; d < 3; ++d) {
    double umax = 0;
    std::array<int, 3> hi{g.end(0), g.end(1), g.end(2)};
    hi[d] += 1;  // the high face of the last owned cell
    for_box({g.begin(0), g.begin(1), g.begin(2)}, hi,
            [&](int i, int j, int k) { umax = std::max(umax, std::abs(uf_[d][g.at(i, j, k)])); });
    for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)},
            [&](int i, int j, int k) { umax = std::max(umax, std::abs(u_[d][g.at(i, j, k)])); });
    rate = std::max(rate, umax / g.h(d));
  }
  rate = g.reduce_max(rate);
  const double inf = std::numeric_limits<double>::infinity();
  double dt = settings_.dt_max;
  limit = "max";
  auto take = [&](double candidate, const char* name) {
    if (candidate < dt) dt = candidate, limit = name;
  };
  if (rate > 0) take(settings_.cfl / rate, "cfl");
  // The viscous limit takes the largest face viscosity over the cell's own density (a gas cell next
  // to the interface sees a face viscosity above the gas's own).
  double nu = 0;
  for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)}, [&](int i, int j, int k) {
    const std::size_t c = g.at(i, j, k);
    // A face between equal viscosities has that viscosity (the harmonic mean's formula only
    // rounds it): the mean is taken where the two differ.
    const double mc = mu_[c];
    double m = mc;
    for (int d = 0; d < 3; ++d)
      for (const double mn : {mu_[c - g.stride(d)], mu_[c + g.stride(d)]})
        if (mn != mc) m = std::max(m, face_viscosity(mc, mn));
    nu = std::max(nu, m / rho_[c]);
  });
  nu = g.reduce_max(nu);
  double inv_h2 = 0, hmin = inf;
  for (int d = 0; d < 3; ++d)
    if (g.cells()[d] > 1 || g.periodic(d)) inv_h2 += 1 / (g.h(d) * g.h(d)), hmin = std::min(hmin, g.h(d));
  if (nu > 0) take(settings_.viscous_number / (2 * nu * inv_h2), "viscous");
  const double gmag = std::sqrt(dot(settings_.gravity, settings_.gravity));
  if (gmag > 0) take(settings_.gravity_number * std::sqrt(hmin / gmag), "gravity");
  if (last_dt_ > 0) take(settings_.dt_growth * last_dt_, "growth");
  return dt;
}

// ---------------------------------------------------------------------------------------------
// Step.
FlowStepStats FlowSolver::advance(double dt) {
  if (!(dt >= settings_.dt_min))
    throw CollectiveRunError("flow time step " + std::to_string(dt) + " s is below fluid.dt.min (" +
                             std::to_string(settings_.dt_min) + " s)");
  FlowStepStats st;
  st.dt = dt;
  wall_impulse_ = {};
  const bool keep = !advection_change_[0].empty();
  if (keep)
    for (int q = 0; q < 3; ++q)
      for (std::size_t c = 0; c < rho_.size(); ++c) advection_change_[q][c] = rho_[c] * u_[q][c];
  // F12a's budget: the energy before and after each stage (only the advection moves mass, so only
  // it changes the potential energy).
  const bool budget = settings_.energy_budget;
  double kinetic = budget ? kinetic_energy() : 0.0;
  const double potential = budget ? potential_energy() : 0.0;
  advect(dt);
  if (budget) {
    const double k = kinetic_energy();
    energy_budget_.advection += (k - kinetic) + (potential_energy() - potential);
    kinetic = k;
  }
  if (keep)
    for (int q = 0; q < 3; ++q)
      for (std::size_t c = 0; c < rho_.size(); ++c) advection_change_[q][c] = rho_[c] * u_[q][c] - advection_change_[q][c];
  if (settings_.liquid.viscosity > 0 || settings_.gas.viscosity > 0) {
    {
      auto t = timers_.scope("viscous");
      viscous(dt);
    }
    if (budget) {
      const double k = kinetic_energy();
      energy_budget_.viscous += k - kinetic;
      kinetic = k;
    }
  }
  st.poisson = project(dt, true);
  if (budget) energy_budget_.projection += kinetic_energy() - kinetic;
  time_ += dt;
  ++steps_;
  last_dt_ = dt;
  return st;
}

PoissonStats FlowSolver::project(double dt, bool with_gravity) {
  const FluidGrid& g = *grid_;
  const Vec3 gravity = with_gravity ? settings_.gravity : Vec3{};
  // A cell drag (in a step, not the initial projection): the cells' and faces' D = lambda dt enter
  // as the density rho (1 + D) of the Poisson equation and the face correction.
  const CellDrag* drag = with_gravity ? drag_ : nullptr;
  const std::vector<double>* rho_p = &rho_;
  if (drag) {
    drag_density_.resize(rho_.size());
    for (std::size_t c = 0; c < rho_.size(); ++c) drag_density_[c] = rho_[c] * (1 + drag->rate[c] * dt);
    rho_p = &drag_density_;
  }
  const std::vector<double>& rho_e = *rho_p;
  // Gravity balanced at the interface (F10b): b_f = g_d where the density does not jump; across a
  // jump, (rho_b (phi_b - phi_I) - rho_a (phi_a - phi_I)) / (h rho_f), phi = g . (x - lo) at the two
  // cells' centres and phi_I at the interface.
  const bool gravity_on = gravity.x != 0 || gravity.y != 0 || gravity.z != 0;
  if (gravity_on) interface_potential();
  // Predicted face velocities (F8), and in face_accel_ the gravity's part b_f of the acceleration.
  for (int d = 0; d < 3; ++d) {
    std::array<int, 3> hi{g.end(0), g.end(1), g.end(2)};
    hi[d] += 1;
    const std::ptrdiff_t st = g.stride(d);
    const int n = g.cells()[d];
    const double h = g.h(d);
    auto& uf = uf_[d];
    auto& b = face_accel_[d];
    const auto& u = u_[d];
    for_box({g.begin(0), g.begin(1), g.begin(2)}, hi, [&](int i, int j, int k) {
      const std::size_t c = g.at(i, j, k);
      const int idx = d == 0 ? i : (d == 1 ? j : k);
      if (!g.periodic(d) && (idx == 0 || idx == n)) {
        const bool low = idx == 0;
        const std::size_t in = low ? c : c - st;
        const bool open = g.boundary(d, low ? 0 : 1) == BoundaryKind::outflow;
        b[c] = open ? gravity[d] : 0.0;
        uf[c] = open ? u[in] + dt * b[c] : 0.0;
        if (drag && open) {
          const double D = drag->rate[in] * dt;
          uf[c] = (uf[c] + D * drag->velocity[d][in]) / (1 + D);
        }
        return;
      }
      const double rho_f = 0.5 * (rho_[c - st] + rho_[c]);
      b[c] = gravity[d];
      const double p0 = gravity_on ? interface_phi_[c - st] : 0.0, p1 = gravity_on ? interface_phi_[c] : 0.0;
      if (gravity_on && rho_[c] != rho_[c - st] && !(std::isnan(p0) && std::isnan(p1))) {
        // The two cells' interface potentials weighted by f (1 - f): a cell holding a round-off
        // residue of liquid has its plane at a corner and must not count. Neither: the face's.
        // Where neither cell holds an interface (both NaN: bulk liquid whose f is within round-off
        // of 1, or a jump on the face itself), the face's potential makes the formula g_d exactly
        // (up to rounding), and b_f = g_d is kept.
        const double w0 = std::isnan(p0) ? 0.0 : f_[c - st] * (1 - f_[c - st]);
        const double w1 = std::isnan(p1) ? 0.0 : f_[c] * (1 - f_[c]);
        const double phi_i = w0 + w1 > 0 ? (w0 * (w0 > 0 ? p0 : 0.0) + w1 * (w1 > 0 ? p1 : 0.0)) / (w0 + w1)
                                         : potential(i + (d == 0 ? 0.0 : 0.5), j + (d == 1 ? 0.0 : 0.5), k + (d == 2 ? 0.0 : 0.5));
        const int ia = i - (d == 0), ja = j - (d == 1), ka = k - (d == 2);  // the cell on the face's low side
        const double phi_a = potential(ia + 0.5, ja + 0.5, ka + 0.5), phi_b = potential(i + 0.5, j + 0.5, k + 0.5);
        b[c] = (rho_[c] * (phi_b - phi_i) - rho_[c - st] * (phi_a - phi_i)) / (h * rho_f);
      }
      if (drag) {  // (rho_f u*_f + mean of rho D U) / mean of rho (1 + D)
        const double pull = 0.5 * (rho_[c - st] * drag->rate[c - st] * drag->velocity[d][c - st] +
                                   rho_[c] * drag->rate[c] * drag->velocity[d][c]) * dt;
        uf[c] = (rho_f * (0.5 * (u[c - st] + u[c]) + dt * b[c]) + pull) / (0.5 * (rho_e[c - st] + rho_e[c]));
      } else {
        uf[c] = 0.5 * (u[c - st] + u[c]) + dt * b[c];
      }
    });
  }
  const double area[3] = {g.h(1) * g.h(2), g.h(0) * g.h(2), g.h(0) * g.h(1)};
  for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)}, [&](int i, int j, int k) {
    const std::size_t c = g.at(i, j, k);
    double outflow = 0;
    for (int d = 0; d < 3; ++d) outflow += (uf_[d][c + g.stride(d)] - uf_[d][c]) * area[d];
    rhs_[c] = -outflow / dt;
  });
  PoissonStats ps;
  {
    auto t = timers_.scope("poisson");
    poisson_->assemble(rho_e);
    ps = poisson_->solve(rhs_, p_);
  }
  auto t = timers_.scope("projection");
  g.exchange(p_);
  fill_pressure_ghosts();
  // Face corrections and face accelerations a_f = g_f - grad_f p / rho_f (F10).
  for (int d = 0; d < 3; ++d) {
    std::array<int, 3> hi{g.end(0), g.end(1), g.end(2)};
    hi[d] += 1;
    const std::ptrdiff_t st = g.stride(d);
    const int n = g.cells()[d];
    const double h = g.h(d);
    auto& uf = uf_[d];
    auto& a = face_accel_[d];
    for_box({g.begin(0), g.begin(1), g.begin(2)}, hi, [&](int i, int j, int k) {
      const std::size_t c = g.at(i, j, k);
      const int idx = d == 0 ? i : (d == 1 ? j : k);
      double grad, rho_f, rho_fe;  // the pressure's gradient; the face's density, and with the drag
      if (!g.periodic(d) && (idx == 0 || idx == n)) {
        const bool low = idx == 0;
        if (g.boundary(d, low ? 0 : 1) != BoundaryKind::outflow) {
          a[c] = 0;  // a wall: its normal velocity, hence acceleration, is zero (b_f was 0)
          return;
        }
        // p = 0 on the outflow face, half a cell from the centre.
        const std::size_t in = low ? c : c - st;
        grad = low ? p_[c] / (0.5 * h) : -p_[c - st] / (0.5 * h);
        rho_f = rho_[in], rho_fe = rho_e[in];
      } else {
        grad = (p_[c] - p_[c - st]) / h;
        rho_f = 0.5 * (rho_[c] + rho_[c - st]), rho_fe = 0.5 * (rho_e[c] + rho_e[c - st]);
      }
      a[c] -= grad / rho_f;  // a_f = b_f - grad p / rho_f
      uf[c] -= dt * (grad / rho_fe);
    });
  }
  if (with_gravity) wall_pressure_impulse(dt);
  for (int d = 0; d < 3; ++d) {
    const std::ptrdiff_t st = g.stride(d);
    for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)}, [&](int i, int j, int k) {
      const std::size_t c = g.at(i, j, k);
      if (drag) {
        const double D = drag->rate[c] * dt;
        u_[d][c] = (u_[d][c] + D * drag->velocity[d][c] + dt * 0.5 * (face_accel_[d][c] + face_accel_[d][c + st])) / (1 + D);
      } else {
        u_[d][c] += dt * 0.5 * (face_accel_[d][c] + face_accel_[d][c + st]);
      }
    });
  }
  g.exchange({&u_[0], &u_[1], &u_[2]});
  fill_velocity_ghosts(u_);
  return ps;
}

void FlowSolver::wall_pressure_impulse(double dt) {
  // A wall face has a_f = 0: the pressure's gradient there balances gravity, so the pressure on the
  // wall is the wall cell's extrapolated half a cell along it, p_c -+ rho_c g_d h_d / 2 (F10). With
  // these values, the projection's momentum change of a fluid of one density is exactly gravity's
  // plus the walls' (interior faces cancel in the sum of the cells' mean face accelerations).
  const FluidGrid& g = *grid_;
  for_wall_layers(g, [&](int d, int side, const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
    const double h = g.h(d), area = g.h(0) * g.h(1) * g.h(2) / h, gd = settings_.gravity[d];
    for_box(lo, hi, [&](int i, int j, int k) {
      const std::size_t c = g.at(i, j, k);
      const double wall = side == 0 ? p_[c] - 0.5 * rho_[c] * gd * h : p_[c] + 0.5 * rho_[c] * gd * h;
      wall_impulse_[d] += (side == 0 ? wall : -wall) * area * dt;
    });
  });
}

Vec3 FlowSolver::last_wall_impulse() const {
  std::array<ExactSum, 3> sums = wall_impulse_;
  ExactSum::all_reduce(sums, grid_->comm());
  return {sums[0].value(), sums[1].value(), sums[2].value()};
}

Vec3 FlowSolver::pressure_force(int i, int j, int k) const {
  const FluidGrid& g = *grid_;
  const std::size_t c = g.at(i, j, k);
  const int idx[3] = {i, j, k};
  Vec3 out;
  for (int d = 0; d < 3; ++d) {
    const std::ptrdiff_t st = g.stride(d);
    const int n = g.cells()[d];
    const double gd = settings_.gravity[d];
    // The face on side s (0 low, 1 high) of the cell: its density as in project().
    auto face = [&](int side) {
      const std::size_t f = side == 0 ? c : c + st;  // faces are stored on their high cell
      const int fidx = idx[d] + side;
      double rho_f;
      if (!g.periodic(d) && (fidx == 0 || fidx == n))
        rho_f = rho_[c];
      else
        rho_f = 0.5 * (rho_[f] + rho_[f - st]);
      return rho_f * (face_accel_[d][f] - gd);
    };
    out[d] = 0.5 * (face(0) + face(1));
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Diagnostics.
double FlowSolver::liquid_volume() const { return grid_->sum_owned(f_) * grid_->cell_volume(); }

double FlowSolver::kinetic_energy() const {
  const FluidGrid& g = *grid_;
  double e = 0;
  for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)}, [&](int i, int j, int k) {
    const std::size_t c = g.at(i, j, k);
    e += 0.5 * rho_[c] * (u_[0][c] * u_[0][c] + u_[1][c] * u_[1][c] + u_[2][c] * u_[2][c]);
  });
  return g.reduce_sum(e) * g.cell_volume();
}

double FlowSolver::potential_energy() const {
  const FluidGrid& g = *grid_;
  double e = 0;
  for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)},
          [&](int i, int j, int k) { e -= rho_[g.at(i, j, k)] * potential(i + 0.5, j + 0.5, k + 0.5); });
  return g.reduce_sum(e) * g.cell_volume();
}

double FlowSolver::max_speed() const {
  const FluidGrid& g = *grid_;
  double m = 0;
  for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)}, [&](int i, int j, int k) {
    const std::size_t c = g.at(i, j, k);
    m = std::max(m, u_[0][c] * u_[0][c] + u_[1][c] * u_[1][c] + u_[2][c] * u_[2][c]);
  });
  return std::sqrt(g.reduce_max(m));
}

double FlowSolver::max_face_divergence() const {
  const FluidGrid& g = *grid_;
  double m = 0;
  for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)}, [&](int i, int j, int k) {
    const std::size_t c = g.at(i, j, k);
    double div = 0;
    for (int d = 0; d < 3; ++d) div += (uf_[d][c + g.stride(d)] - uf_[d][c]) / g.h(d);
    m = std::max(m, std::abs(div));
  });
  return g.reduce_max(m);
}

double FlowSolver::boundary_flux(int d, int side) const {
  const FluidGrid& g = *grid_;
  ExactSum sum;
  if (g.at_domain_edge(d, side)) {
    std::array<int, 3> lo{g.begin(0), g.begin(1), g.begin(2)}, hi{g.end(0), g.end(1), g.end(2)};
    lo[d] = side == 0 ? 0 : g.cells()[d];  // the face below cell lo[d]: the domain's side
    hi[d] = lo[d] + 1;
    const double area = g.cell_volume() / g.h(d), sign = side == 0 ? -1.0 : 1.0;
    for_box(lo, hi, [&](int i, int j, int k) { sum.add(sign * area * uf_[d][g.at(i, j, k)]); });
  }
  sum.all_reduce(g.comm());
  return sum.value();
}

double FlowSolver::min_fraction() const {
  const FluidGrid& g = *grid_;
  double m = std::numeric_limits<double>::infinity();
  for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)},
          [&](int i, int j, int k) { m = std::min(m, f_[g.at(i, j, k)]); });
  return g.reduce_min(m);
}

double FlowSolver::max_fraction() const {
  const FluidGrid& g = *grid_;
  double m = -std::numeric_limits<double>::infinity();
  for_box({g.begin(0), g.begin(1), g.begin(2)}, {g.end(0), g.end(1), g.end(2)},
          [&](int i, int j, int k) { m = std::max(m, f_[g.at(i, j, k)]); });
  return g.reduce_max(m);
}

}  // namespace tessera
