// The solvers of a scene wired together (include/sphfem/sim/simulation.h).
#include "sphfem/sim/simulation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "sphfem/scene/bodies.h"
#include "sphfem/scene/compile.h"

namespace sphfem {

const BodiesModel& Simulation::bodies_model() const {
  static const BodiesModel kNone;
  return bodies_model_ ? *bodies_model_ : kNone;
}

Simulation::Simulation(const SceneSpec& scene, Backend backend) : scene_(scene) {
  if (!scene.has_fluid() && scene.bodies.empty())
    throw std::runtime_error(
        "the scene has nothing to simulate; add fluid.blocks, fluid.emitters or bodies");
  obstacles_ = compile_obstacles(scene, scene.path);
  if (scene.has_fluid()) fluid_model_ = compile_fluid(scene);
  if (!scene.bodies.empty()) {
    bodies_model_ = std::make_shared<const BodiesModel>(compile_scene_bodies(scene));
    bodies_ = make_body_solver(bodies_model_, backend);
  }
  if (scene.has_fluid()) {
    if (bodies_) carved_ = carve_bodies(fluid_model_, *bodies_model_);
    carved_ += carve_obstacles(fluid_model_, obstacles_);
    fluid_ = make_fluid_solver(fluid_model_, backend);
  }
  // The coupling's stages run whenever fluid meets a surface: bodies (either coupling), or
  // the tank's faces in the ray cast even in a scene without bodies.
  const bool rays = scene.coupling.method == CouplingMethod::RayTraced;
  if (fluid_ && (bodies_ || (rays && (scene.coupling.tank_rays || !obstacles_.empty())))) {
    RayCouplingSettings cs = ray_coupling_settings(scene);
    cs.obstacle_x = obstacles_.at(0);
    cs.obstacle_tris = obstacles_.tris;
    cs.obstacle_offset = obstacles_.tri_offset;
    cs.obstacle_coeffs = obstacles_.coeffs;
    cs.obstacle_closed = obstacles_.closed;
    const bool solids =
        std::find(obstacles_.closed.begin(), obstacles_.closed.end(), 1) != obstacles_.closed.end();
    cs.near_surface = cs.near_surface && (bodies_ != nullptr || solids);
    cs.support = fluid_model_.params.h;
    coupling_ = make_ray_coupling(cs, bodies_.get(), backend);
    // The baseline: samples a particle spacing apart on every body surface (Akinci et al.).
    if (!rays && bodies_)
      fluid_->set_moving_samples(sample_surface(bodies_model_->x0, bodies_model_->surface,
                                                double(fluid_model_.params.spacing)),
                                 bodies_model_->surface, bodies_model_->nodes);
  }
  if (fluid_ && bodies_) inside_check_ = make_collider(Backend::Cpu);
  if (bodies_ && scene.fem.contact) {
    ContactSettings cs;
    cs.gap = scene.fem.contact_gap;
    cs.friction = scene.fem.friction;
    contact_ = std::make_unique<SurfaceContact>(*bodies_model_, cs);
  }
  if (bodies_ && !obstacles_.empty()) {
    ObstacleGroup still;
    for (int k = 0; k < obstacles_.count(); ++k) {
      const auto first = obstacles_.tris.begin() + obstacles_.tri_offset[std::size_t(k)];
      const auto last = obstacles_.tris.begin() + obstacles_.tri_offset[std::size_t(k) + 1];
      if (!obstacles_.moves(k)) {
        still.tris.insert(still.tris.end(), first, last);
        continue;
      }
      ObstacleGroup g;
      g.obstacle = k;
      g.tris.assign(first, last);
      obstacle_groups_.push_back(std::move(g));
    }
    if (!still.tris.empty()) obstacle_groups_.insert(obstacle_groups_.begin(), std::move(still));
    for (ObstacleGroup& g : obstacle_groups_) {
      g.collider = make_collider(Backend::Cpu);
      g.collider->build(obstacles_.x, g.tris);
      g.collider->refit(obstacles_.x, obstacles_.x);
    }
  }
}

// A fluid block overlapping a body would start with particles inside it or pressed into its
// surface, which the first steps shoot out at many metres per second; the body displaces
// them instead. Kept: particles outside every body at least a particle radius from it.
namespace {

// Leaves out the initial particles within a particle radius of the surface, and inside it when
// it bounds a solid.
long carve(FluidModel& fluid, const std::vector<Vec3>& x, const std::vector<Tri>& tris,
           bool solid) {
  if (fluid.x0.empty() || tris.empty()) return 0;
  auto collider = make_collider(Backend::Cpu);
  collider->build(x, tris);
  const std::vector<std::uint8_t> in =
      solid ? collider->inside(fluid.x0) : std::vector<std::uint8_t>(fluid.x0.size(), 0);
  const std::vector<collide::ClosestHit> near =
      collider->closest(fluid.x0, fluid.params.spacing / 2);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < fluid.x0.size(); ++i) {
    if (in[i] || near[i].face >= 0) continue;
    fluid.x0[kept] = fluid.x0[i];
    fluid.v0[kept] = fluid.v0[i];
    ++kept;
  }
  const long removed = long(fluid.x0.size() - kept);
  fluid.x0.resize(kept);
  fluid.v0.resize(kept);
  fluid.x0.shrink_to_fit();
  fluid.v0.shrink_to_fit();
  return removed;
}

}  // namespace

long carve_bodies(FluidModel& fluid, const BodiesModel& bodies) {
  return carve(fluid, bodies.x0, bodies.surface, true);
}

long carve_obstacles(FluidModel& fluid, const ObstaclesModel& obstacles) {
  long removed = 0;
  const std::vector<Vec3> x = obstacles.at(0);
  for (std::size_t k = 0; k + 1 < obstacles.tri_offset.size(); ++k) {
    const std::vector<Tri> tris(obstacles.tris.begin() + obstacles.tri_offset[k],
                                obstacles.tris.begin() + obstacles.tri_offset[k + 1]);
    removed += carve(fluid, x, tris, obstacles.closed[k] != 0);
  }
  return removed;
}

double Simulation::time() const { return fluid_ ? fluid_->time() : t_bodies_; }

long Simulation::steps() const { return fluid_ ? fluid_->steps() : bodies_ ? bodies_->steps() : 0; }

template <class F>
void Simulation::timed(Stage s, F&& fn) {
  const auto t0 = std::chrono::steady_clock::now();
  set_stage_label(stage_name(s));
  fn();
  set_stage_label(nullptr);
  profile_.ms[int(s)] +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// One step (paper §3-4 with the corrections of docs/design.md), stage by stage. The fluid
// keeps its particle order from sort() to the end of the step; every stage finishes its work
// before the next begins.
StepInfo Simulation::step(double dt_limit) {
  StepInfo info;
  ++profile_.steps;
  if (!fluid_) {  // bodies alone, in steps of dt_limit
    info.dt = dt_limit;
    t_step_ = t_bodies_;
    step_bodies(dt_limit);
    t_bodies_ += dt_limit;
    return info;
  }
  FluidSolver& f = *fluid_;
  RayCoupling* c = coupling_.get();
  timed(Stage::Neighbors, [&] { f.sort(c ? c->moving_boundary(f.arrays()) : MovingSurface()); });
  SurfaceProximity near;
  if (c) timed(Stage::Proximity, [&] { near = c->proximity(f.arrays()); });
  timed(Stage::Density, [&] { f.density(near); });
  const double dt = f.time_step(dt_limit, info);
  t_step_ = f.time();
  timed(Stage::Divergence, [&] { f.divergence(info); });
  timed(Stage::Forces, [&] { f.forces(info); });
  timed(Stage::Pressure, [&] {
    f.pressure(info);
    if (c) c->before_bodies(f.arrays());
  });
  if (bodies_) step_bodies(dt);
  DriftLimits limits;
  if (c)
    timed(Stage::Collide, [&] {
      if (obstacles_.moving())
        c->move_obstacles(obstacles_.at(t_step_), obstacles_.at(t_step_ + dt), dt);
      limits = c->cast(f.arrays(), dt);
    });
  timed(Stage::Drift, [&] { f.drift(limits, info); });
  if (c) {
    timed(Stage::ContactFix, [&] { c->fix_contacts(f.arrays()); });
    timed(Stage::Exchange, [&] { c->exchange(f.arrays()); });
  }
  timed(Stage::Emit, [&] { f.emit(info); });
  return info;
}

// The bodies over the step, in halves where their surfaces met too deep (step_bodies_span).
void Simulation::step_bodies(double dt) {
  ContactStats step;
  step_bodies_span(t_step_, dt, 0, step);
  if (contact_) last_contact_ = step;
}

// [t0, t0 + dt] in one implicit step, or, when its surface contact found a pair deeper than
// kHalvingDepth of the rest height of the pair's elements or the step left more elements
// inside out than it began with, again from its start in two halves, each of which may halve
// again (fem.contact_halvings times). A push of a node through most of its own element's
// height turns the element inside out: two soft balls closing at 4 m/s in steps of 1.33 ms
// left 46 elements inverted, in steps of 0.33 ms none; the bunny's fold, closing on itself,
// still turned two small elements at a depth within bounds, which a shorter step does not.
// The fluid's impulses for the step are in the saved state, so the first half takes them.
// `step` gathers the contact of the halves kept: the most pairs, the smallest gap, the
// deepest pair.
void Simulation::step_bodies_span(double t0, double dt, int halvings, ContactStats& step) {
  const BodyContactTally tally = tally_;
  step_bodies_once(t0, dt);
  const bool may_halve = contact_ && halvings < scene_.fem.contact_halvings;
  bool turned = false;
  if (may_halve) {
    BodySnapshot s;
    bodies_->snapshot(s);
    const int now = inverted_elements(*bodies_model_, s.x);
    turned = now > 0 && now > inverted_elements(*bodies_model_, step_start_.x);
  }
  if (may_halve && (last_contact_.depth_ratio > kHalvingDepth || turned)) {
    tally_ = tally;  // the step not kept counts for nothing but the halving
    ++tally_.halvings;
    bodies_->load(step_start_);
    step_bodies_span(t0, 0.5 * dt, halvings + 1, step);
    step_bodies_span(t0 + 0.5 * dt, 0.5 * dt, halvings + 1, step);
    return;
  }
  step.pairs = std::max(step.pairs, last_contact_.pairs);
  step.rounds = std::max(step.rounds, last_contact_.rounds);
  step.nodes = std::max(step.nodes, last_contact_.nodes);
  step.min_gap = std::min(step.min_gap, last_contact_.min_gap);
  step.depth_ratio = std::max(step.depth_ratio, last_contact_.depth_ratio);
}

// The implicit step, then what it cannot see: obstacles, and surfaces meeting each other.
// Surface contact is found after the step; when there is some, the step is taken again from
// its start with the contact's impulses in it, so the whole body feels them within the step
// (an impulse on the surface alone, after it, lets the body run on into the squeezed surface
// and the elastic energy grows past what the motion brought), and the contact is resolved
// once more after it.
void Simulation::step_bodies_once(double t0, double dt) {
  std::vector<Vec3> before;
  const bool contacts = !obstacle_groups_.empty() || contact_;
  BodyStepInfo b;
  auto implicit_step = [&] {
    try {
      b = bodies_->step(dt);
    } catch (const std::runtime_error& e) {
      throw BodyStepError(e.what());  // the solver's own check: a non-finite right-hand side
    }
    if (!std::isfinite(b.cg_residual)) throw BodyStepError("the body solve became non-finite");
  };
  ++tally_.steps;
  timed(Stage::Fem, [&] {
    if (contacts) {
      BodySnapshot s;
      bodies_->snapshot(s);
      before = std::move(s.x);
    }
    if (contact_) bodies_->save(step_start_);
    implicit_step();
  });
  if (!contacts) {
    tally_.held += b.held;
    return;
  }
  timed(Stage::BodyContact, [&] {
    BodySnapshot s;
    std::vector<std::uint8_t> moved;
    auto resolve = [&] {
      bodies_->snapshot(s);
      moved.assign(s.x.size(), 0);
      if (!obstacle_groups_.empty()) collide_obstacles(before, s.x, s.v, moved, t0, dt);
      if (!contact_) return;
      std::vector<std::uint8_t> pushed;
      last_contact_ = contact_->resolve(before, s.x, s.v, dt, pushed);
      for (std::size_t i = 0; i < moved.size(); ++i) moved[i] |= pushed[i];
    };
    resolve();
    // Each pass adds the impulses the contact still had to apply after the last one: the
    // body's response to an impulse inside the step is softer than a free node's, so one pass
    // leaves fast approaches still closing.
    std::vector<Vec3> J;
    const ContactStats first = last_contact_;
    for (int pass = 0; contact_ && pass < kContactPasses && last_contact_.pairs > 0; ++pass) {
      const std::vector<Vec3> v_after = s.v;
      bodies_->snapshot(s);  // the velocities the step gave, before any contact
      J.resize(s.v.size());
      const std::vector<Real>& mass = bodies_model_->mass;
      for (std::size_t i = 0; i < J.size(); ++i) J[i] += (v_after[i] - s.v[i]) * mass[i];
      bodies_->load(step_start_);
      bodies_->add_node_impulses(J);
      implicit_step();
      resolve();
      if (!(last_contact_.min_gap < 0.5 * contact_->gap())) break;  // closing no more
    }
    last_contact_.pairs = std::max(last_contact_.pairs, first.pairs);
    last_contact_.depth_ratio = first.depth_ratio;  // what the step met, before its passes
    std::vector<int> nodes;
    std::vector<Vec3> x, v;
    for (std::size_t i = 0; i < moved.size(); ++i)
      if (moved[i]) {
        nodes.push_back(int(i));
        x.push_back(s.x[i]);
        v.push_back(s.v[i]);
      }
    if (!nodes.empty()) bodies_->set_nodes(nodes, x, v);
  });
  tally_.held += b.held;
  tally_.pairs += last_contact_.pairs;
  tally_.min_gap = std::min(tally_.min_gap, last_contact_.min_gap);
}

BodyContactTally Simulation::take_body_contact_tally() {
  const BodyContactTally t = tally_;
  tally_ = BodyContactTally();
  return t;
}

// Nodes whose path over the step met an obstacle's face go back to the side they came from, a
// small gap off the face; the velocity into the face (relative to the face's own) is removed
// and the tangential one loses fem.friction times the removed normal speed (Coulomb, as on the
// tank's walls). Done on the host after the step: a projection, like the walls', not a
// constraint inside the solve. An obstacle on a path is met in its own frame: each node's path
// relative to it, from where the node was in the obstacle's start pose to where it is in the
// end pose, as a ray against its faces as placed.
void Simulation::collide_obstacles(const std::vector<Vec3>& before, std::vector<Vec3>& xs,
                                   std::vector<Vec3>& vs, std::vector<std::uint8_t>& moved,
                                   double t0, double dt) {
  const Real gap = Real(1e-5 * norm(scene_.domain.hi - scene_.domain.lo));
  const std::size_t n = xs.size();
  struct Hit {
    int group = -1, face = -1;
    Real fraction = 2, t = 0;  // of the relative path; distance along it
  };
  std::vector<Hit> best(n);
  std::vector<RigidPose> start(obstacle_groups_.size()), end(obstacle_groups_.size());
  std::vector<Vec3> from(n), dir(n);
  std::vector<Real> len(n);
  for (std::size_t g = 0; g < obstacle_groups_.size(); ++g) {
    const ObstacleGroup& group = obstacle_groups_[g];
    if (group.obstacle >= 0) {
      start[g] = obstacles_.pose(group.obstacle, t0);
      end[g] = obstacles_.pose(group.obstacle, t0 + dt);
    }
    for (std::size_t i = 0; i < n; ++i) {
      from[i] = start[g].inverse(before[i]);
      const Vec3 d = end[g].inverse(xs[i]) - from[i];
      len[i] = norm(d);
      dir[i] = len[i] > Real(0) ? d / len[i] : Vec3(0, 1, 0);
    }
    const std::vector<collide::RayHit> hit = group.collider->cast_rays(from, dir, len);
    for (std::size_t i = 0; i < n; ++i) {
      if (hit[i].face < 0 || !(len[i] > Real(0))) continue;
      const Real fraction = hit[i].t / len[i];
      if (fraction < best[i].fraction) best[i] = Hit{int(g), hit[i].face, fraction, hit[i].t};
    }
  }
  const Real mu = Real(scene_.fem.friction);
  const std::vector<std::uint8_t>& pinned = bodies_model_->pinned;
  for (std::size_t i = 0; i < n; ++i) {
    // A pinned node is held (infinite mass): an obstacle on a path meeting it does not move it.
    if (best[i].group < 0 || (i < pinned.size() && pinned[i])) continue;
    const std::size_t g = std::size_t(best[i].group);
    const RigidPose &p0 = start[g], &p1 = end[g];
    const Tri& t = obstacle_groups_[g].tris[std::size_t(best[i].face)];
    const Vec3 a = obstacles_.x[std::size_t(t.v[0])], b = obstacles_.x[std::size_t(t.v[1])],
               c = obstacles_.x[std::size_t(t.v[2])];
    // In the obstacle's frame: the contact point, and the normal toward the node's side.
    const Vec3 local = p0.inverse(before[i]);
    const Vec3 d = p1.inverse(xs[i]) - local;
    const Vec3 q = local + d / norm(d) * best[i].t;
    Vec3 nl = cross(b - a, c - a);
    nl = nl / norm(nl);
    if (dot(local - a, nl) < Real(0)) nl = -nl;
    const Vec3 p = p1.apply(q);
    const Vec3 nrm = p1.identity ? nl : Vec3(p1.rotate(Vec3d(nl)));
    // The face's velocity at the contact point over the step (zero for one that stays put).
    const Vec3 w = (p - p0.apply(q)) / Real(dt);
    Vec3 vr = vs[i] - w;
    const Real vn = dot(vr, nrm);
    if (vn < Real(0)) {
      const Vec3 vt = vr - nrm * vn;
      const Real st = norm(vt);
      const Real keep = st > -mu * vn ? Real(1) + mu * vn / st : Real(0);
      vr = vt * keep;
    }
    xs[i] = p + nrm * gap;
    vs[i] = w + vr;
    moved[i] = 1;
  }
}

void Simulation::reset_profile() {
  profile_.clear();
  if (fluid_) fluid_->reset_profile();
  if (bodies_) bodies_->reset_profile();
}

void Simulation::snapshot(FluidSnapshot& out) {
  if (!fluid_) {
    out = FluidSnapshot();
    return;
  }
  fluid_->snapshot(out, coupling_.get());
}

void Simulation::save(SimState& s) const {
  s = SimState();
  s.time = t_bodies_;
  s.has_fluid = fluid_ != nullptr;
  s.has_bodies = bodies_ != nullptr;
  if (fluid_) fluid_->save(s.fluid);
  if (bodies_) bodies_->save(s.bodies);
}

void Simulation::load(const SimState& s) {
  if (s.has_fluid != (fluid_ != nullptr) || s.has_bodies != (bodies_ != nullptr))
    throw std::invalid_argument(std::string("state: ") + (s.has_fluid ? "with" : "without") +
                                " fluid and " + (s.has_bodies ? "with" : "without") +
                                " bodies, the scene is otherwise");
  if (fluid_) fluid_->load(s.fluid);
  if (bodies_) bodies_->load(s.bodies);
  t_bodies_ = s.time;
  if (coupling_) coupling_->bodies_moved();
}

long Simulation::count_inside() {
  if (!inside_check_) return 0;
  FluidSnapshot f;
  snapshot(f);
  if (f.n == 0) return 0;
  BodySnapshot b;
  bodies_->snapshot(b);
  return count_inside(f.x, b.x);
}

long Simulation::count_inside(const std::vector<Vec3>& particles, const std::vector<Vec3>& nodes) {
  if (!inside_check_ || particles.empty()) return 0;
  inside_check_->build(nodes, bodies_model_->surface);
  long n = 0;
  for (std::uint8_t in : inside_check_->inside(particles)) n += in;
  return n;
}

}  // namespace sphfem
