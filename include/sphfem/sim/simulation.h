// A scene's solvers wired together: the fluid, the bodies and the coupling between them, as
// `sphfem run`, `sphfem view` and the benchmarks step them. Frames, gauges and progress stay
// with the runner (run.h).
#pragma once

#include <memory>
#include <vector>

#include "sphfem/collide/collider.h"
#include "sphfem/couple/ray_coupling.h"
#include "sphfem/fem/model.h"
#include "sphfem/fem/solver.h"
#include "sphfem/scene/spec.h"
#include "sphfem/sph/model.h"
#include "sphfem/sph/solver.h"

namespace sphfem {

class Simulation {
 public:
  // Compiles the scene's fluid and bodies and builds the solvers; throws SceneError or
  // std::runtime_error on input that cannot run (before anything is stepped).
  Simulation(const SceneSpec& scene, Backend backend);

  // One step: the fluid's (CFL-limited, at most dt_limit) with the bodies inside it when the
  // coupling is ray-traced; bodies alone (no fluid) take dt_limit. Throws SimulationError,
  // and BodyStepError when a body's solve is not finite.
  StepInfo step(double dt_limit);
  double time() const;

  // Particles inside a body's closed surface now (a host BVH over the current positions).
  long count_inside();
  // The same for given particle and body-node positions (snapshots already taken).
  long count_inside(const std::vector<Vec3>& particles, const std::vector<Vec3>& nodes);

  const SceneSpec& scene() const { return scene_; }
  FluidSolver* fluid() { return fluid_.get(); }
  BodySolver* bodies() { return bodies_.get(); }
  RayCoupling* coupling() { return hook_.get(); }
  const FluidModel& fluid_model() const { return fluid_model_; }
  const BodiesModel& bodies_model() const { return bodies_model_; }
  // True when the bodies step inside the fluid step (ray-traced coupling with fluid).
  bool bodies_in_fluid_step() const { return hook_ && bodies_; }

 private:
  SceneSpec scene_;
  FluidModel fluid_model_;
  BodiesModel bodies_model_;
  std::unique_ptr<FluidSolver> fluid_;
  std::unique_ptr<BodySolver> bodies_;
  std::unique_ptr<RayCoupling> hook_;
  std::unique_ptr<Collider> inside_check_;
  double t_bodies_ = 0;  // without fluid
};

// The coupling settings a scene asks for.
RayCouplingSettings ray_coupling_settings(const SceneSpec& scene);

}  // namespace sphfem
