// The solvers of a scene wired together (include/sphfem/sim/simulation.h).
#include "sphfem/sim/simulation.h"

#include <cmath>
#include <stdexcept>

#include "sphfem/scene/bodies.h"

namespace sphfem {

RayCouplingSettings ray_coupling_settings(const SceneSpec& scene) {
  RayCouplingSettings cs;
  cs.rays = scene.coupling.method == CouplingMethod::RayTraced;
  // The baseline's samples stand for the bodies; the tank keeps its own samples.
  cs.near_surface = cs.rays && scene.coupling.near_surface_density;
  cs.skin = Real(scene.coupling.skin * scene.fluid.particle_radius);
  cs.tank = cs.rays && scene.coupling.tank_rays;
  cs.tank_lo = Vec3(scene.domain.lo);
  cs.tank_hi = Vec3(scene.domain.hi);
  cs.open_top = scene.domain.open_top;
  cs.wall = ContactCoeffs{Real(scene.coupling.wall_restitution), Real(scene.coupling.wall_slip)};
  for (const BodySpec& b : scene.bodies)
    cs.body.push_back(ContactCoeffs{Real(b.restitution), Real(b.slip)});
  cs.rebuild_quality = scene.coupling.rebuild_quality;
  return cs;
}

Simulation::Simulation(const SceneSpec& scene, Backend backend) : scene_(scene) {
  if (!scene.has_fluid() && scene.bodies.empty())
    throw std::runtime_error(
        "the scene has nothing to simulate; add fluid.blocks, fluid.emitters or bodies");
  if (scene.has_fluid()) {
    fluid_model_ = compile_fluid(scene);
    fluid_ = make_fluid_solver(fluid_model_, backend);
  }
  if (!scene.bodies.empty()) {
    bodies_model_ = compile_scene_bodies(scene);
    bodies_ = make_body_solver(bodies_model_, backend);
  }
  // With fluid, the bodies step inside the fluid step (the hook), for either coupling; the
  // tank's faces can join the ray cast even in a scene without bodies.
  const bool rays = scene.coupling.method == CouplingMethod::RayTraced;
  if (fluid_ && (bodies_ || (rays && scene.coupling.tank_rays))) {
    RayCouplingSettings cs = ray_coupling_settings(scene);
    cs.near_surface = cs.near_surface && bodies_ != nullptr;
    cs.support = fluid_model_.params.h;
    hook_ = make_ray_coupling(cs, bodies_.get(), backend);
    fluid_->set_hook(hook_.get());
    // The baseline: samples a particle spacing apart on every body surface (Akinci et al.).
    if (!rays && bodies_)
      fluid_->set_moving_samples(sample_surface(bodies_model_.x0, bodies_model_.surface,
                                                double(fluid_model_.params.spacing)),
                                 bodies_model_.surface, bodies_model_.nodes);
  }
  if (fluid_ && bodies_) inside_check_ = make_collider(Backend::Cpu);
}

double Simulation::time() const { return fluid_ ? fluid_->time() : t_bodies_; }

StepInfo Simulation::step(double dt_limit) {
  StepInfo info;
  if (fluid_) {
    info = fluid_->step(dt_limit);
  } else {
    info.dt = dt_limit;
  }
  if (bodies_ && !bodies_in_fluid_step()) {
    BodyStepInfo b;
    try {
      b = bodies_->step(info.dt);
    } catch (const std::runtime_error& e) {
      throw BodyStepError(e.what());  // the solver's own check: a non-finite right-hand side
    }
    if (!std::isfinite(b.cg_residual)) throw BodyStepError("the body solve became non-finite");
  }
  if (!fluid_) t_bodies_ += info.dt;
  return info;
}

long Simulation::count_inside() {
  if (!inside_check_) return 0;
  FluidSnapshot f;
  fluid_->snapshot(f);
  if (f.n == 0) return 0;
  BodySnapshot b;
  bodies_->snapshot(b);
  return count_inside(f.x, b.x);
}

long Simulation::count_inside(const std::vector<Vec3>& particles, const std::vector<Vec3>& nodes) {
  if (!inside_check_ || particles.empty()) return 0;
  inside_check_->build(nodes, bodies_model_.surface);
  long n = 0;
  for (std::uint8_t in : inside_check_->inside(particles)) n += in;
  return n;
}

}  // namespace sphfem
