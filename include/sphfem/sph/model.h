// The compiled fluid model: everything a solver needs, derived once from a scene (by
// compile_fluid in scene/compile.h; the fluid itself knows nothing of scenes).
// Model apart from state: this is immutable during a run; FluidSolver owns the state.
#pragma once

#include <vector>

#include "sphfem/core/vec.h"
#include "sphfem/sph/kernels.h"
#include "sphfem/sph/solver_kind.h"

namespace sphfem {

// Plain values copied into every kernel launch.
struct SphParams {
  Kernel kernel;
  Real h = 0, h2 = 0;  // support radius and its square
  Real spacing = 0;    // lattice spacing d = 2 * particle radius
  Real mass = 0;       // per particle, so a full lattice has exactly rest density
  Real rho0 = 0;
  Real volume = 0;       // mass / rho0
  Real stiffness = 0;    // WCSPH: p = stiffness * (rho/rho0 - 1), p >= 0
  Real sound_speed = 0;  // sqrt(stiffness / rho0)
  Real viscosity = 0;    // kinematic, m^2/s
  Real xsph = 0;
  Real alpha_av = 0;  // Monaghan artificial viscosity
  Vec3 gravity;
  Vec3 clamp_lo, clamp_hi;  // last-resort box no particle may leave (the tank's inner faces)
  int full_neighbors = 0;   // neighbours of a particle inside a full lattice
};

struct GridGeometry {
  Vec3 lo;
  Real cell = 0;
  int nx = 0, ny = 0, nz = 0;
  long long cells() const { return (long long)nx * ny * nz; }
};

struct EmitterModel {
  Vec3 position, direction;
  Real speed = 0, start = 0, end = 0;
  Real layer_spacing = 0;  // distance travelled between two emitted layers
  std::vector<Vec3> disc;  // offsets of one layer's particles from the nozzle centre
};

struct FluidModel {
  SphParams params;
  SolverKind solver = SolverKind::DFSPH;
  double dt_min = 0, dt_max = 0, cfl = 0.4;
  double density_tolerance = 1e-3, divergence_tolerance = 1e-3;
  int max_iterations = 100;
  GridGeometry grid;
  std::vector<Vec3> x0, v0;        // initial particles (blocks)
  std::vector<Vec3> boundary_x;    // static wall samples
  std::vector<Real> boundary_psi;  // their mass contribution (Akinci et al. 2012 psi)
  std::vector<EmitterModel> emitters;
  int capacity = 0;  // most particles the run can hold
};

// Particle mass giving rest density on a cubic lattice of the given spacing (kernel sum).
Real lattice_mass(const Kernel& kernel, Real spacing, Real rho0);

}  // namespace sphfem
