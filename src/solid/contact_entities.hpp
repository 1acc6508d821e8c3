// SPDX-License-Identifier: MIT
// The DEM's contact entities and the contact kernel's view of them (T13). An entity is a body (a
// sphere, or a disc in plane mode) or, when the case declares shape templates, one contact sphere
// of a body (an element: element e of body i sits at x_i + R(q_i) c_e and moves with
// v_i + w_i x R(q_i) c_e). This class owns:
//   - the element layout of the local bodies (owned, then ghosts): each element's body, permanent
//     key (body order * key_stride + sphere index, contact_history.hpp) and radius;
//   - the kernel's mirrors of the entities' positions and motion this step, and the contact buffer
//     every contact stage adds its reactions to (kernel_mirrors.hpp: 3D per element, or one disc
//     line per body in plane mode);
// and answers the questions every contact stage asks of an entity: where it is, how it moves, its
// key, radius, body, material and mass, and where its reaction goes.
#pragma once
#include <cstdint>
#include <vector>

#include "solid/contact_kernel.hpp"
#include "solid/kernel_mirrors.hpp"
#include "solid/particles.hpp"
#include "solid/shape.hpp"

namespace tessera {

class ContactEntities {
 public:
  explicit ContactEntities(const ParticleStore& bodies) : p_(bodies) {}
  ContactEntities(const ContactEntities&) = delete;
  ContactEntities& operator=(const ContactEntities&) = delete;

  // Shaped: the entities are elements; discs (plane mode, sphere bodies): one disc mirror per body.
  void configure(bool shaped, int plane_normal) { shaped_ = shaped, normal_ = shaped ? -1 : plane_normal; }
  bool shaped() const { return shaped_; }
  bool discs() const { return normal_ >= 0; }
  int plane_normal() const { return normal_; }  // discs: the plane's normal axis
  const ParticleStore& bodies() const { return p_; }

  // Shaped mode, after a rebuild (ghosts in place): the elements of every local body, placed.
  void layout(const std::vector<ShapeTemplate>& shapes, std::int64_t key_stride);
  // Shaped mode: the positions of the elements of bodies [first, end) from their x and q.
  void place(const std::vector<ShapeTemplate>& shapes, std::size_t first, std::size_t end);
  // Shaped mode: the positions of the elements [first, last) (sorted indices) alone.
  void place_listed(const std::vector<ShapeTemplate>& shapes, const std::int32_t* first, const std::int32_t* last);
  // Element e's position now from its body's x and q (the value place() writes), mirror or not.
  Vec3 position(const std::vector<ShapeTemplate>& shapes, std::size_t e) const;

  std::size_t owned() const { return shaped_ ? e_owned_ : p_.owned; }  // entities of owned bodies
  std::size_t size() const { return shaped_ ? e_body_.size() : p_.size(); }
  std::size_t body(std::size_t e) const { return shaped_ ? static_cast<std::size_t>(e_body_[e]) : e; }
  double radius(std::size_t e) const { return shaped_ ? e_r_[e] : p_.radius[e]; }
  std::int64_t key(std::size_t e) const { return shaped_ ? e_key_[e] : p_.order[e]; }
  int material(std::size_t e) const { return p_.material[body(e)]; }
  double mass(std::size_t e) const { return p_.mass[body(e)]; }
  // Shaped mode, for the list build: per element, its body, key and radius.
  const std::vector<std::int32_t>& element_body() const { return e_body_; }
  const std::vector<std::int64_t>& element_key() const { return e_key_; }
  const std::vector<double>& element_radius() const { return e_r_; }
  // Shaped mode: how far body i's elements reach from its centre (farthest centre plus radius).
  double element_reach(std::size_t i) const { return e_reach_[i]; }

  // Position and radius, and motion, as the contacts read them this step (the mirrors'; a disc's
  // from the body arrays).
  KernelGeometry geometry(std::size_t e) const {
    if (!discs()) return geometry_[e];
    return {p_.x[3 * e], p_.x[3 * e + 1], p_.x[3 * e + 2], p_.radius[e]};
  }
  Vec3 centre(std::size_t e) const {
    if (!shaped_) return p_.pos(e);
    return {geometry_[e].x, geometry_[e].y, geometry_[e].z};
  }
  KernelMotion motion(std::size_t e) const {
    if (!discs()) return motion_[e];
    const double *v = &p_.v[3 * e], *w = &p_.omega[3 * e];
    return {v[0], v[1], v[2], w[0], w[1], w[2]};
  }
  // Shaped mode: element e's motion from its body's (made only for elements in contact).
  void refresh_motion(std::size_t e);

  // The mirrors and the contact buffer (the integrator packs the owned bodies' mirrors, the pair
  // loop the rest).
  std::vector<KernelGeometry>& geometry_mirrors() { return geometry_; }
  std::vector<KernelMotion>& motion_mirrors() { return motion_; }
  std::vector<KernelForce>& forces() { return force_; }  // per local body
  std::vector<DiscMirror>& disc_mirrors() { return disc_; }
  std::vector<DiscForce>& disc_forces() { return disc_force_; }  // per local body
  // Before the pair stage: mirrors for every local entity, the contact buffer emptied.
  void start_forces();

  // The contact buffer's total on body i as a 3D force and torque.
  KernelForce load(std::size_t i) const {
    if (!discs()) return force_[i];
    double f[6] = {0, 0, 0, 0, 0, 0};
    const DiscForce& d = disc_force_[i];
    f[plane_u(normal_)] = d.fu, f[plane_v(normal_)] = d.fv, f[3 + normal_] = d.tn;
    return {f[0], f[1], f[2], f[3], f[4], f[5]};
  }
  // A wall-type contact's force (lane j: force and n x force) on the body of entity e, with the
  // lever-arm torque in shaped mode.
  void add_wall_reaction(std::size_t e, const ContactLanes& L, std::size_t j) {
    if (discs()) {
      const double* f[3] = {L.fx, L.fy, L.fz};
      const double* nf[3] = {L.nx, L.ny, L.nz};
      DiscForce& fo = disc_force_[e];
      fo.fu += f[plane_u(normal_)][j], fo.fv += f[plane_v(normal_)][j];
      fo.tn -= nf[normal_][j] * L.ra[j];
      return;
    }
    const std::size_t b = body(e);
    KernelForce& fo = force_[b];
    fo.fx += L.fx[j], fo.fy += L.fy[j], fo.fz += L.fz[j];
    fo.tx -= L.nx[j] * L.ra[j], fo.ty -= L.ny[j] * L.ra[j], fo.tz -= L.nz[j] * L.ra[j];
    if (shaped_) add_lever(fo, geometry_[e], b, L.fx[j], L.fy[j], L.fz[j]);
  }
  // Shaped mode: adds the torque (x_e - x_body) x F of an element force to the body's slot.
  void add_lever(KernelForce& f, const KernelGeometry& g, std::size_t body, double fx, double fy, double fz) const {
    const double ax = g.x - p_.x[3 * body], ay = g.y - p_.x[3 * body + 1], az = g.z - p_.x[3 * body + 2];
    f.tx += ay * fz - az * fy, f.ty += az * fx - ax * fz, f.tz += ax * fy - ay * fx;
  }

 private:
  const ParticleStore& p_;
  bool shaped_ = false;
  int normal_ = -1;  // discs: the plane's normal axis
  std::vector<std::int32_t> e_body_;  // local body of each element
  std::vector<std::int64_t> e_key_;
  std::vector<double> e_r_;
  std::vector<std::size_t> e_first_;  // per local body: its first element (size bodies + 1)
  std::size_t e_owned_ = 0;
  std::vector<double> e_reach_;  // per local body (shaped mode): see element_reach
  std::vector<KernelGeometry> geometry_;
  std::vector<KernelMotion> motion_;
  std::vector<KernelForce> force_;
  std::vector<DiscMirror> disc_;
  std::vector<DiscForce> disc_force_;
};

}  // namespace tessera
