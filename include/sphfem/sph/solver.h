// The fluid solver behind one interface for every backend. The physics is written once in
// src/sph/stages.h and instantiated for the CPU (solver_cpu.cpp) and CUDA (solver_cuda.cu).
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "sphfem/core/backend.h"
#include "sphfem/core/memory.h"
#include "sphfem/core/profile.h"
#include "sphfem/sph/model.h"
#include "sphfem/sph/moving_boundary.h"
#include "sphfem/sph/state.h"

namespace sphfem {

// A run that cannot go on (NaN, blow-up); the message says at which step and what to change.
struct SimulationError : std::runtime_error {
  long step;
  SimulationError(long step_, const std::string& what) : std::runtime_error(what), step(step_) {}
};

struct StepInfo {
  double dt = 0;
  int pressure_iterations = 0;
  int divergence_iterations = 0;
  // DFSPH: mean residual of the density solve over fluid and wall samples: relative
  // compression, or expansion a particle's remaining pressure still holds open.
  double density_error = 0;
  int clamped = 0;  // particles the last-resort box had to stop this step
  int emitted = 0;
};

struct FluidSnapshot {
  int n = 0;
  std::vector<Vec3> x, v;
  std::vector<Real> rho, p;
  std::vector<std::uint32_t> id;
  std::vector<int> neighbors;  // fluid neighbours within the support, self included
};

// The particles as a StepHook sees them, in the solver's memory space (device pointers under
// CUDA). The order changes every step (particles are re-sorted by grid cell at its start), but
// not between a step's before_drift and after_drift; id is the stable particle name.
struct FluidArrays {
  MemSpace space = MemSpace::Host;
  int n = 0;
  Vec3* x = nullptr;
  Vec3* v = nullptr;
  const std::uint32_t* id = nullptr;
  Real mass = 0;    // per particle
  Real radius = 0;  // half the lattice spacing
};

// What a hook may ask of the drift, per particle (nullptr: nothing). travel in [0, 1] scales
// the displacement relative to surface_v (paper eq. 6 for rays cast relative to a moving
// surface): x += dt (s + travel (v - s)), s = surface_v or 0.
struct DriftLimits {
  const Real* travel = nullptr;
  const Vec3* surface_v = nullptr;
};

// The closest body surface of every particle, for the near-surface density
// (sph/surface_density.h): per particle in the step's order, in the solver's memory space.
// dist (m, >= 0) to the closest surface point and the unit normal there, pointing from the
// surface to the particle; dist >= the support radius or a zero normal: no surface in reach.
// velocity: of that surface point (nullptr: at rest). dv (optional, zeroed by the hook): the
// step adds the velocity change the surface's pressure gave each particle, so that the hook
// can return the opposite impulse to the surface and momentum is exchanged, not created.
struct SurfaceProximity {
  const Real* dist = nullptr;
  const Vec3* normal = nullptr;
  const Vec3* velocity = nullptr;
  Vec3* dv = nullptr;
  // The surface's slip coefficient C_s (nullptr: 1, free slip): below 1 the surface drags the
  // particle's tangential velocity toward its own (stages::surface_drag).
  const Real* slip = nullptr;
};

// What a fluid step asks of the solid surfaces around it, at the particles' present positions:
// the boundary-particle baseline's sampled surface, and each particle's closest surface for
// the near-surface density. Queries only: snapshot() asks them too.
class SurfaceQuery {
 public:
  virtual ~SurfaceQuery() = default;
  virtual MovingSurface moving_boundary(const FluidArrays&) { return MovingSurface(); }
  virtual SurfaceProximity proximity(const FluidArrays&) { return SurfaceProximity(); }
};

// Code run inside FluidSolver::step for a fluid alone with a solid of its own (tests, simple
// embeddings); a coupled scene is stepped by Simulation::step, stage by stage, instead.
// before_drift returns the drift's limits (arrays valid until after_drift), after_drift
// follows it. The backend's work must be finished when a call returns.
class StepHook : public SurfaceQuery {
 public:
  virtual DriftLimits before_drift(const FluidArrays& fluid, double dt) = 0;
  virtual void after_drift(const FluidArrays& fluid, double dt) = 0;
};

class FluidSolver {
 public:
  virtual ~FluidSolver() = default;
  virtual int count() const = 0;
  virtual double time() const = 0;
  virtual long steps() const = 0;

  // One step of at most dt_limit seconds (and the CFL limit): the stages below in order, with
  // the hook (if any) around the drift. Throws SimulationError.
  virtual StepInfo step(double dt_limit) = 0;

  // The stages of one step, in the order Simulation::step calls them (core/profile.h). Each
  // finishes its work before it returns; the particles keep their order from sort() to the
  // end of the step.
  // Boundary samples placed on `moving` (the baseline; empty: none), particles re-sorted by
  // grid cell.
  virtual void sort(const MovingSurface& moving) = 0;
  // Neighbour lists and densities, with the near-surface density of `near` (kept for the
  // step's later stages; its dv collects the surface pressure's velocity change).
  virtual void density(const SurfaceProximity& near) = 0;
  // The step's length: the CFL limit capped by dt_max and dt_limit. Throws SimulationError.
  virtual double time_step(double dt_limit, StepInfo& info) = 0;
  virtual void divergence(StepInfo& info) = 0;  // DFSPH divergence solve; WCSPH: nothing
  virtual void forces(StepInfo& info) = 0;      // non-pressure forces (WCSPH: all), kick
  // DFSPH density solve (v becomes v*); then the samples' impulse into moving.impulse.
  virtual void pressure(StepInfo& info) = 0;
  // x += dt v*, limited by `limits`, then the last-resort box; time advances.
  virtual void drift(const DriftLimits& limits, StepInfo& info) = 0;
  virtual void emit(StepInfo& info) = 0;
  // The particles in the step's order, in the solver's memory space.
  virtual FluidArrays arrays() = 0;

  // The particles with density, pressure and neighbour counts at their present positions
  // (surfaces from `surfaces`, else the hook's). Changes no state: a step after it gives the
  // same bits as without it.
  virtual void snapshot(FluidSnapshot& out, SurfaceQuery* surfaces = nullptr) = 0;
  // The state's exact image (sph/state.h); load() continues from it bit for bit. load()
  // throws std::invalid_argument for a state that does not fit this model.
  virtual void save(FluidState& out) const = 0;
  virtual void load(const FluidState& in) = 0;

  virtual const StepProfile& profile() const = 0;
  virtual void reset_profile() = 0;
  // The model the solver was made from, less its arrays x0, v0, boundary_x and boundary_psi:
  // the solver's buffers hold those (save() gives the particles).
  virtual const FluidModel& model() const = 0;
  // Emitter e (fluid.emitters[e]) emits within its start..end window only while enabled, as
  // a valve would; all are enabled at construction. A control input, not part of the saved
  // state. Both throw std::out_of_range for an emitter the scene does not have.
  virtual void set_emitter_enabled(int e, bool enabled) = 0;
  virtual bool emitter_enabled(int e) const = 0;
  // Runs hook inside every step() from now on (nullptr: none); not owned, must outlive its use.
  virtual void set_hook(StepHook* hook) = 0;
  // Boundary-particle coupling: samples (sample_surface) on the triangles tris of a surface
  // of `nodes` nodes, placed every step on the surface sort() is given. Replaces the samples
  // set before; empty: none. Throws std::invalid_argument for a triangle or node out of range.
  virtual void set_moving_samples(const std::vector<SurfaceSample>& samples,
                                  const std::vector<Tri>& tris, int nodes) = 0;
};

// Throws std::runtime_error when the backend is not usable here (e.g. CUDA without a GPU).
std::unique_ptr<FluidSolver> make_fluid_solver(const FluidModel& model, Backend backend);

}  // namespace sphfem
