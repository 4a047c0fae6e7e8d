// A scene's solvers wired together: the fluid, the bodies and the coupling between them, as
// `sphfem run`, `sphfem view` and the benchmarks step them. Frames, gauges and progress stay
// with the runner (run.h).
#pragma once

#include <limits>
#include <memory>
#include <vector>

#include "sphfem/collide/collider.h"
#include "sphfem/core/profile.h"
#include "sphfem/couple/ray_coupling.h"
#include "sphfem/fem/contact.h"
#include "sphfem/fem/model.h"
#include "sphfem/fem/solver.h"
#include "sphfem/scene/compile.h"
#include "sphfem/scene/obstacles.h"
#include "sphfem/scene/spec.h"
#include "sphfem/sim/state.h"
#include "sphfem/sph/model.h"
#include "sphfem/sph/solver.h"

namespace sphfem {

// What the bodies' contacts did over the steps since the last take_body_contact_tally().
struct BodyContactTally {
  long steps = 0;
  long pairs = 0;  // surface contact pairs (fem/contact.h), summed over the steps
  long held = 0;   // nodes the tank's walls held inside the solve, summed over the steps
  double min_gap = std::numeric_limits<double>::infinity();  // m, over the steps' pairs
  long halvings = 0;  // body steps taken again in two halves (surfaces met too deep)
};

// One coupled step is Simulation::step, read top to bottom: its stages (core/profile.h) are
// named calls on the fluid solver, the body solver and the coupling, each timed into one
// StepProfile. The compiled models are fixed at construction; the state lives in the solvers
// (in the backend's memory) and save()/load() give its exact plain image (sim/state.h).
class Simulation {
 public:
  // Compiles the scene's fluid and bodies and builds the solvers; throws SceneError or
  // std::runtime_error on input that cannot run (before anything is stepped).
  Simulation(const SceneSpec& scene, Backend backend);

  // One step: the fluid's (CFL-limited, at most dt_limit) with the bodies taking the same dt;
  // bodies alone (no fluid) take dt_limit. Throws SimulationError, and BodyStepError when a
  // body's solve is not finite.
  StepInfo step(double dt_limit);
  double time() const;
  long steps() const;

  // The fluid at its present positions (densities from the coupling's surfaces too). Reading
  // changes no state.
  void snapshot(FluidSnapshot& out);

  // The state's exact image, and continuing from one (of a Simulation of the same scene).
  // load() throws std::invalid_argument for a state that does not fit.
  void save(SimState& out) const;
  void load(const SimState& in);

  // Control between steps (src/sim/simulation_control.cpp). Emitter e (fluid.emitters[e]) on
  // or off, a valve on its start..end window; throws std::out_of_range for an emitter the
  // scene lacks (or a scene without fluid).
  void set_emitter_enabled(int e, bool enabled);
  bool emitter_enabled(int e) const;
  // The pinned nodes of scene.bodies[body], as global node indices (BodiesModel order);
  // throws std::out_of_range for a body the scene lacks.
  std::vector<int> pinned_nodes(int body) const;
  // Moves pinned nodes (global indices) to the positions x, e.g. a tool pushing the body: the
  // free nodes follow through the elastic forces of the next steps. A move is applied at once,
  // so a large one strains the elements next to it as much; move in steps of a few mm.
  // Throws std::invalid_argument for sizes that differ or a node out of range or not pinned.
  void move_pinned(const std::vector<int>& nodes, const std::vector<Vec3d>& x);

  const StepProfile& profile() const { return profile_; }
  void reset_profile();

  // Particles inside a body's closed surface now (a host BVH over the current positions).
  long count_inside();
  // The same for given particle and body-node positions (snapshots already taken).
  long count_inside(const std::vector<Vec3>& particles, const std::vector<Vec3>& nodes);

  const SceneSpec& scene() const { return scene_; }
  FluidSolver* fluid() { return fluid_.get(); }
  BodySolver* bodies() { return bodies_.get(); }
  RayCoupling* coupling() { return coupling_.get(); }
  const FluidModel& fluid_model() const { return fluid_model_; }
  // Initial particles left out because they lay inside a body or against its surface.
  long carved_particles() const { return carved_; }
  const BodiesModel& bodies_model() const;
  const ObstaclesModel& obstacles() const { return obstacles_; }
  // The last step's surface contact (empty stats without fem.contact or bodies); the gap the
  // surfaces keep (0 without).
  const ContactStats& last_contact() const { return last_contact_; }
  // The contacts since the last call, and a fresh count from now on.
  BodyContactTally take_body_contact_tally();
  double contact_gap() const { return contact_ ? contact_->gap() : 0.0; }

 private:
  template <class F>
  void timed(Stage s, F&& fn);
  void step_bodies(double dt);
  void step_bodies_span(double t0, double dt, int halvings, ContactStats& step);
  void step_bodies_once(double t0, double dt);
  void collide_obstacles(const std::vector<Vec3>& before, std::vector<Vec3>& x,
                         std::vector<Vec3>& v, std::vector<std::uint8_t>& moved, double t0,
                         double dt);

  // Body nodes against the obstacles: the ones that stay put together, in the scene's frame,
  // and each one on a path alone, in its own frame as placed (obstacle >= 0).
  struct ObstacleGroup {
    int obstacle = -1;
    std::vector<Tri> tris;
    std::unique_ptr<Collider> collider;
  };

  SceneSpec scene_;
  FluidModel fluid_model_;
  std::shared_ptr<const BodiesModel> bodies_model_;  // shared with the body solver
  std::unique_ptr<FluidSolver> fluid_;
  std::unique_ptr<BodySolver> bodies_;
  std::unique_ptr<RayCoupling> coupling_;
  std::unique_ptr<Collider> inside_check_;
  ObstaclesModel obstacles_;
  std::vector<ObstacleGroup> obstacle_groups_;
  std::unique_ptr<SurfaceContact> contact_;  // body surfaces against each other
  ContactStats last_contact_;
  BodyState step_start_;  // the bodies at the start of the step, for its contact pass
  BodyContactTally tally_;
  static constexpr int kContactPasses = 3;      // implicit steps again with the contact's impulses
  static constexpr double kHalvingDepth = 0.5;  // step_bodies_span: deepest pair / rest height
  StepProfile profile_;
  double t_bodies_ = 0;  // without fluid
  double t_step_ = 0;    // when the step being taken began
  long carved_ = 0;
};

// Removes the initial particles inside a body's rest surface or closer to it than a particle
// radius; returns how many.
long carve_bodies(FluidModel& fluid, const BodiesModel& bodies);
// The same around the obstacles (inside only for the closed ones).
long carve_obstacles(FluidModel& fluid, const ObstaclesModel& obstacles);

}  // namespace sphfem
