// Boundary samples on moving triangle surfaces: the boundary-particle coupling of Akinci et
// al. 2012 ("Versatile rigid-fluid coupling for incompressible SPH"), the baseline the
// paper's ray-traced coupling is compared with (paper §5.2, Fig. 8).
//
// Each sample is fixed on one triangle by barycentric weights, so its position and velocity
// follow the triangle's nodes every step, and the impulse the fluid gives it returns to those
// nodes by the same weights: the fluid and the nodes exchange momentum exactly. The samples
// act on the fluid through the same code as the tank's wall samples (src/sph/stages.h), with
// Akinci's psi = rho0 / sum_k W_bk over the samples around each one, taken every step.
// Under DFSPH a sample also carries a stiffness, weighted by psi like the fluid's term, and
// its density constraint counts the layer behind it at the share that the fluid resting in
// front of it completes to rho0 (stages::moving_rest_share, src/sph/moving_stages.h).
#pragma once

#include <vector>

#include "sphfem/core/memory.h"
#include "sphfem/core/vec.h"
#include "sphfem/fem/mesh.h"

namespace sphfem {

// x = w[0] x(v[0]) + w[1] x(v[1]) + w[2] x(v[2]) of triangle tri; the weights sum to 1.
struct SurfaceSample {
  int tri = 0;
  Real w[3] = {1, 0, 0};
};

// Samples about `spacing` apart over every triangle: the triangle is cut into n^2 similar
// triangles, n = ceil(longest edge / spacing), and their corners become samples. Corners a
// neighbouring triangle shares (its vertices, and its edge points where both sides cut the
// edge alike) are kept once; where the cuts differ, samples closer than the spacing remain,
// and psi evens out their weight. Throws std::invalid_argument for spacing <= 0 or a node
// index out of range.
std::vector<SurfaceSample> sample_surface(const std::vector<Vec3d>& x, const std::vector<Tri>& tris,
                                          double spacing);
std::vector<SurfaceSample> sample_surface(const std::vector<Vec3>& x, const std::vector<Tri>& tris,
                                          double spacing);

// The nodes of the sampled surface as a StepHook hands them to the solver each step, in the
// solver's memory space (device pointers under CUDA).
struct MovingSurface {
  MemSpace space = MemSpace::Host;
  int nodes = 0;             // 0: no samples this step
  const Tri* tri = nullptr;  // the triangles given to FluidSolver::set_moving_samples
  const Vec3* x = nullptr;   // node positions at the start of the step
  const Vec3* v = nullptr;   // node velocities (nullptr: at rest)
  // N s per node: the step adds the fluid's impulse on the samples here, by their weights,
  // before StepHook::before_drift (nullptr: not returned).
  Vec3* impulse = nullptr;
};

}  // namespace sphfem
