// SPDX-License-Identifier: MIT
// The bunker shot (bunker-shot seed, issue 5; docs/theory.md T16-T18): a sand wedge swung about a
// pivot through a plane bed of sand discs in which a ball (a free sphere, T17) rests.
// The swing starts where the head's lowest point clears the bed's highest grain by
// `start_clearance` (2 mm), or at `start_angle_deg` when given.
//
// Start: a checkpoint of the bed with the ball at rest (`bed.file`, from ball_small.yaml or the
// like). The club is placed as the seed places it (section 4.1): the pivot on the vertical through
// the ball's centre, `shaft_length` above the point the leading edge passes at the bottom of the
// swing, which is the ball's lowest point moved `shot_depth` down (Table 2: 0 to 10 mm). The swing
// starts (theta, 0 with the club vertical; negative behind the ball; see set_start_angle) with
// theta' = `angular_velocity`, and follows eq. 8 with the club's mass and moment of inertia per
// unit depth times the plane's thickness.
//
// Per step: the club's upward impulse J = sum F_z dt (the bodies' load on the club) and the
// ball's release. Release moment: the step of the ball's largest speed in the run before it first
// touches a wall of the domain (the seed's box is 150 mm high: a ball struck upwards reaches the lid
// within a millisecond of leaving the sand). The club and the sand accelerate the ball up to it;
// afterwards only gravity (0.01 m/s per ms) or drag through sand slow it down. Release angle =
// atan2(v_z, v_x) there, release speed = |v|.
// (A first definition, the first contact-free step, fired at 1.7 ms in the small case: the sand
// the club pushes ahead lifts the ball off for a moment long before the club arrives.)
// Quantities: release_angle_deg, release_speed_mps, release_time, ball_free_at_end, club_upward_impulse
// (J / (m_club omega_0 L): the impulse over the club head's initial momentum, the same for any
// slice thickness: the seed's non-dimensional impulse), club_upward_impulse_Ns_per_m (J per metre
// of depth), club_angular_velocity_loss (omega_0 - omega_end, rad/s) and its fraction; the ball's
// time series in ball.csv.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>

#include "app/dem_scene.hpp"
#include "app/scenes.hpp"
#include "core/errors.hpp"
#include "core/h5_file.hpp"
#include "solid/club_head.hpp"
#include "solid/dem_io.hpp"

namespace tessera {

namespace {

constexpr double kDeg = std::numbers::pi / 180;

class BunkerShotScene final : public DemScene {
 public:
  BunkerShotScene(const ConfigNode& root, MPI_Comm comm, const std::string& case_dir) : DemScene(root, comm, case_dir) {
    const ConfigNode b = root.section("bed");
    file_ = resolve_path(b.text("file"));
    if (!std::filesystem::is_regular_file(file_) || std::filesystem::path(file_).extension() != ".h5")
      b.fail("file", "an existing Tessera checkpoint of the bed with the ball at rest (" + file_ + ")");
    if (!dem_->plane_mode()) root.section("solid").fail("plane", "plane mode (the seed's shot is 2D)");
    const ConfigNode c = root.section("club");
    design_.loft_deg = c.real("loft_deg", Dim::none, Range::half_open(0, 90), design_.loft_deg);
    design_.bounce_deg = c.real("bounce_deg", Dim::none, Range::half_open(0, 45), design_.bounce_deg);
    design_.face_length = c.real("face_length", Dim::length, Range::positive(), design_.face_length);
    design_.sole_width = c.real("sole_width", Dim::length, Range::positive(), design_.sole_width);
    design_.sole_camber = c.real("sole_camber", Dim::length, Range::non_negative(), design_.sole_camber);
    depth_ = c.real("shot_depth", Dim::length, Range{-0.05, 0.05, true, true}, 0.0);
    shaft_ = c.real("shaft_length", Dim::length, Range::positive(), 0.7);
    omega0_ = c.real("angular_velocity", Dim::angular_velocity, Range::positive(), 50.0);
    if (c.has("start_angle_deg")) start_deg_ = c.real("start_angle_deg", Dim::none, Range{-90.0, 0.0, true, false});
    clearance_ = c.real("start_clearance", Dim::length, Range::non_negative(), clearance_);
    mass_per_depth_ = c.real("mass_per_depth", Dim::none, Range::positive());
    inertia_per_depth_ = c.real("moment_of_inertia_per_depth", Dim::none, Range::positive());
    applied_moment_per_depth_ = c.real("applied_moment_per_depth", Dim::none, Range{-1e300, 1e300, false, false}, 0.0);
    material_ = dem_->model().material_index(c.text("material"), c.key_path("material"));
    const std::string ball = c.text("ball", "ball");
    for (std::size_t k = 0; k < dem_->free_spheres().size(); ++k)
      if (dem_->free_spheres()[k].key == ball) ball_ = static_cast<int>(k);
    if (ball_ < 0) c.fail("ball", "the key of a free sphere in solid.free_spheres ('" + ball + "' is not one)");
    if (const auto out = root.optional_section("output"))
      series_interval_ = out->real("series_interval", Dim::time, Range::positive(), series_interval_);
    // The club exists before any checkpoint is read (a restart reads its state into it): its
    // reference comes from the ball's resting place in the bed file.
    add_club(ball_rest_position(root.section("bed")));
  }
  const char* name() const override { return "bunker_shot"; }

 protected:
  void create_bodies() override {
    // The bed file has no club: set it aside while the bed and the ball are read.
    auto& meshes = dem_->walls().meshes();
    MeshWall club = std::move(meshes.back());
    meshes.pop_back();
    read_checkpoint(file_, *dem_);
    meshes.push_back(std::move(club));
    dem_->set_clock(0.0, 0);
    set_start_angle();
  }
  bool continues_state() const override { return true; }

  void on_step(const RunOptions& opt) override {
    const MeshWall& club = dem_->walls().meshes().back();
    const FreeSphere& ball = dem_->free_spheres()[static_cast<std::size_t>(ball_)];
    impulse_ += club.force.z * dem_->dt();
    const double speed = norm(ball.v);
    hit_wall_ = hit_wall_ || ball.touches_wall;
    if (!hit_wall_ && speed > norm(release_v_)) {
      release_time_ = dem_->time();
      release_v_ = ball.v;
    }
    if (dem_->time() >= next_series_ - 0.5 * dem_->dt()) {
      next_series_ += series_interval_;
      if (dem_->decomposition().rank() == 0) {
        if (!series_) {
          series_ = std::make_unique<std::ofstream>(opt.output_dir + "/ball.csv",
                                                    opt.restart ? std::ios::app : std::ios::trunc);
          if (!opt.restart)
            *series_ << "time,ball_x,ball_z,ball_vx,ball_vz,ball_spin,ball_contact_fx,ball_contact_fz,club_angle,"
                        "club_angular_velocity,club_fx,club_fz,club_upward_impulse\n";
        }
        const int n = dem_->plane_normal();
        const double spin = ball.omega[n];
        *series_ << dem_->time() << ',' << ball.x.x << ',' << ball.x.z << ',' << ball.v.x << ',' << ball.v.z << ','
                 << spin << ',' << ball.force.x << ',' << ball.force.z << ',' << club.theta << ',' << club.theta_dot
                 << ',' << club.force.x << ',' << club.force.z << ',' << impulse_ / momentum() << '\n';
      }
    }
  }

  void finish(const RunOptions& opt) override {
    (void)opt;
    if (series_) series_->flush();
  }

  void quantities(nlohmann::json& q) override {
    const MeshWall& club = dem_->walls().meshes().back();
    const FreeSphere& ball = dem_->free_spheres()[static_cast<std::size_t>(ball_)];
    const Vec3 v = release_v_;
    q["ball_free_at_end"] = ball.force.x == 0.0 && ball.force.y == 0.0 && ball.force.z == 0.0;
    q["release_time"] = release_time_;
    q["ball_hit_wall"] = hit_wall_;
    q["release_angle_deg"] = std::atan2(v.z, v.x) / kDeg;
    q["release_speed_mps"] = norm(v);
    q["ball_end_velocity"] = {ball.v.x, ball.v.z};
    q["ball_end_position"] = {ball.x.x, ball.x.z};
    q["club_upward_impulse"] = impulse_ / momentum();
    q["club_upward_impulse_Ns_per_m"] = impulse_ / dem_->plane_thickness();
    q["club_angular_velocity_loss"] = omega0_ - club.theta_dot;
    q["club_angular_velocity_loss_fraction"] = (omega0_ - club.theta_dot) / omega0_;
    q["club_end_angle_deg"] = club.theta / kDeg;
    q["pivot"] = {pivot_.x, pivot_.z};
    q["leading_edge_bottom"] = {pivot_.x, pivot_.z - shaft_};
    q["club_mass"] = club.mass;
    q["club_start_angle_deg"] = start_deg_ ? *start_deg_ : start_used_deg_;
  }

  CheckpointExtras extras() const override {
    return {{"impulse", impulse_},         {"release_time", release_time_}, {"hit_wall", hit_wall_ ? 1.0 : 0.0},
            {"release_vx", release_v_.x},  {"release_vy", release_v_.y},    {"release_vz", release_v_.z},
            {"next_series", next_series_}, {"start_deg", start_used_deg_}};
  }
  void restore(const CheckpointExtras& e) override {
    auto get = [&](const char* k) {
      const auto it = e.find(k);
      if (it == e.end()) throw InputError("restart", k, "a bunker_shot checkpoint");
      return it->second;
    };
    impulse_ = get("impulse"), release_time_ = get("release_time"), hit_wall_ = get("hit_wall") != 0.0;
    start_used_deg_ = get("start_deg");
    release_v_ = {get("release_vx"), get("release_vy"), get("release_vz")};
    next_series_ = get("next_series");
  }

 private:
  // Club head momentum at the start, m omega_0 L (per slice): the impulse's scale.
  double momentum() const { return mass_per_depth_ * dem_->plane_thickness() * omega0_ * shaft_; }

  Vec3 ball_rest_position(const ConfigNode& bed) const {
    H5File f = H5File::open_read(file_, dem_->decomposition().comm());
    if (!f.has("free_sphere_state"))
      bed.fail("file", "a checkpoint with the ball at rest (run ball_small.yaml first): " + file_ + " has no ball");
    int cols = 0;
    const auto state = f.read_all<double>("free_sphere_state", cols);
    const std::size_t row = static_cast<std::size_t>(ball_) * static_cast<std::size_t>(cols);
    if (cols < 3 || state.size() < row + 3) bed.fail("file", "a checkpoint with the case's free spheres");
    return {state[row], state[row + 1], state[row + 2]};
  }

  void add_club(const Vec3& ball) {
    const FreeSphere& b = dem_->free_spheres()[static_cast<std::size_t>(ball_)];
    const int n = dem_->plane_normal();
    if (n != 1) throw InputError("solid.plane.normal", "", "y for the bunker shot (the swing is in x-z)");
    const double t = dem_->plane_thickness();
    // Leading edge at the bottom of the swing, and the pivot above it.
    const Vec3 edge{ball.x, ball.y, ball.z - b.radius - depth_};
    pivot_ = {edge.x, edge.y, edge.z + shaft_};
    MeshWall m;
    m.key = "club";
    m.material = material_;
    m.motion = MeshWall::Motion::pivot;
    // theta' > 0 carries the head forward (+x) at the bottom: about -y.
    m.axis = {0, -1, 0};
    m.inertia = inertia_per_depth_ * t;
    m.mass = mass_per_depth_ * t;
    m.applied_moment = applied_moment_per_depth_ * t;
    m.origin = pivot_;
    // The head's area centroid is its centre of mass (a uniform head; the shaft's share is in the
    // moment of inertia only).
    const auto outline = club_head_outline(design_);
    double area = 0, cx = 0, cz = 0;
    for (std::size_t k = 0; k < outline.size(); ++k) {
      const auto& p = outline[k];
      const auto& q = outline[(k + 1) % outline.size()];
      const double c = p[0] * q[1] - q[0] * p[1];
      area += c, cx += (p[0] + q[0]) * c, cz += (p[1] + q[1]) * c;
    }
    m.centre_of_mass = Vec3{edge.x + cx / (3 * area), 0, edge.z + cz / (3 * area)} - pivot_;
    std::vector<Vec3> nodes;
    // Wider than the slice, so that the disc's whole thickness meets the side surface.
    extrude_outline(outline, ball.y, 4 * t, nodes, m.triangles);
    for (const auto& p : nodes) m.local.push_back(Vec3{p.x + edge.x, p.y, p.z + edge.z} - pivot_);
    m.theta_dot = omega0_;
    dem_->walls().add_mesh(m);  // q0 = identity: the club vertical
  }

  static void turn(MeshWall& club, double theta) {
    club.theta = theta;
    club.q = Quaternion{std::cos(0.5 * theta), club.axis.x * std::sin(0.5 * theta), club.axis.y * std::sin(0.5 * theta),
                        club.axis.z * std::sin(0.5 * theta)};
    club.place();
  }

  // The swing's start: start_angle_deg if given; otherwise the angle nearest the bottom (in 0.01 deg)
  // at which the head's lowest point is start_clearance above the bed's highest grain, so that
  // the club enters the sand moving, whatever the depth and the design (collective).
  void set_start_angle() {
    MeshWall& club = dem_->walls().meshes().back();
    if (start_deg_) {
      turn(club, *start_deg_ * kDeg);
      return;
    }
    const ParticleStore& p = dem_->particles();
    double top = -1e300;
    for (std::size_t i = 0; i < p.owned; ++i) top = std::max(top, p.x[3 * i + 2] + p.radius[i]);
    MPI_Allreduce(MPI_IN_PLACE, &top, 1, MPI_DOUBLE, MPI_MAX, dem_->decomposition().comm());
    auto lowest = [&](double theta) {
      turn(club, theta);
      double z = 1e300;
      for (const auto& n : club.nodes) z = std::min(z, n.z);
      return z;
    };
    int step = 0;
    while (lowest(-step * 0.01 * kDeg) < top + clearance_) {
      if (++step > 9000) throw InputError("club.start_clearance", "", "a start above the bed within 90 degrees");
    }
    start_used_deg_ = -step * 0.01;
  }

  std::string file_;
  ClubHeadDesign design_;
  double depth_ = 0, shaft_ = 0.7, omega0_ = 50;
  std::optional<double> start_deg_;
  double clearance_ = 0.002, start_used_deg_ = 0;
  double mass_per_depth_ = 0, inertia_per_depth_ = 0, applied_moment_per_depth_ = 0;
  int material_ = 0, ball_ = -1;
  Vec3 pivot_;
  double series_interval_ = 1e-4, next_series_ = 0;
  double impulse_ = 0, release_time_ = 0;
  Vec3 release_v_;         // the ball's velocity at its largest speed so far, before any wall
  bool hit_wall_ = false;  // the ball has touched a wall of the domain (the lid, in the seed's box)
  std::unique_ptr<std::ofstream> series_;
};

}  // namespace

std::unique_ptr<DemScene> make_bunker_shot_scene(const ConfigNode& root, MPI_Comm comm, const std::string& dir) {
  return std::make_unique<BunkerShotScene>(root, comm, dir);
}

}  // namespace tessera
