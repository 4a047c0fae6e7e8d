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
#include "sphfem/sph/model.h"
#include "sphfem/sph/moving_boundary.h"

namespace sphfem {

// A run that cannot go on (NaN, blow-up); the message says at which step and what to change.
struct SimulationError : std::runtime_error {
  long step;
  SimulationError(long step_, const std::string& what) : std::runtime_error(what), step(step_) {}
};

// Coupling: the time a StepHook takes (with bodies: their step, the ray casts and impulses).
enum class Phase {
  Neighbors,
  Density,
  Divergence,
  Forces,
  Pressure,
  Integrate,
  Emit,
  Coupling,
  Count
};
const char* phase_name(Phase p);

struct Profile {
  double ms[int(Phase::Count)] = {};
  long steps = 0;
  void clear() { *this = Profile(); }
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
};

// Code run inside a fluid step, for two-way coupling. The step is:
//   moving_boundary   boundary-particle coupling: where the sampled surface is now
//   sort              particles re-ordered by grid cell
//   proximity         ray-traced coupling: each particle's closest surface
//   density, forces and pressure (v becomes v*); the samples' impulse goes to the nodes
//   before_drift, drift (x += dt v* limited by the returned DriftLimits, then the last-resort
//   box), after_drift, emit.
// A coupler steps the bodies over the same dt, casts rays and returns travel fractions in
// before_drift, and exchanges impulses in after_drift. Arrays returned must stay valid until
// after_drift; the backend's work must be finished when a call returns. moving_boundary and
// proximity are queries of the present state: snapshot() calls them too (after its own sort).
class StepHook {
 public:
  virtual ~StepHook() = default;
  virtual MovingSurface moving_boundary(const FluidArrays&) { return MovingSurface(); }
  virtual SurfaceProximity proximity(const FluidArrays&) { return SurfaceProximity(); }
  virtual DriftLimits before_drift(const FluidArrays& fluid, double dt) = 0;
  virtual void after_drift(const FluidArrays& fluid, double dt) = 0;
};

class FluidSolver {
 public:
  virtual ~FluidSolver() = default;
  virtual int count() const = 0;
  virtual double time() const = 0;
  virtual long steps() const = 0;
  // One step of at most dt_limit seconds (and the CFL limit). Throws SimulationError.
  virtual StepInfo step(double dt_limit) = 0;
  virtual void snapshot(FluidSnapshot& out) = 0;
  virtual const Profile& profile() const = 0;
  virtual void reset_profile() = 0;
  virtual const FluidModel& model() const = 0;
  // Runs hook inside every step from now on (nullptr: none); not owned, must outlive its use.
  virtual void set_hook(StepHook* hook) = 0;
  // Boundary-particle coupling: samples (sample_surface) on the triangles tris of a surface
  // of `nodes` nodes, placed every step at the hook's moving_boundary. Replaces the samples
  // set before; empty: none. Throws std::invalid_argument for a triangle or node out of range.
  virtual void set_moving_samples(const std::vector<SurfaceSample>& samples,
                                  const std::vector<Tri>& tris, int nodes) = 0;
};

// Throws std::runtime_error when the backend is not usable here (e.g. CUDA without a GPU).
std::unique_ptr<FluidSolver> make_fluid_solver(const FluidModel& model, Backend backend);

}  // namespace sphfem
