// The compiled deformable-body model: everything the FEM solver needs, derived once from the
// rest meshes and materials. Model apart from state: this is immutable during a run; the
// positions, velocities and element rotations live in the BodySolver.
//
// Several bodies share one simulation: compile_bodies concatenates their nodes and elements
// into flat arrays (global node indices, per-body offsets), so one set of kernels steps all.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sphfem/core/vec.h"
#include "sphfem/fem/mat3.h"
#include "sphfem/fem/mesh.h"

namespace sphfem {

struct Material {
  double density = 1000.0;  // kg/m^3
  double young = 1e5;       // Pa, Young's modulus E
  double poisson = 0.3;     // Poisson's ratio, -1 < nu < 0.5
  double alpha = 0.0;       // 1/s, Rayleigh damping D = alpha M + beta K
  double beta = 0.0;        // s
};

// Lame parameters of a material (linear isotropic elasticity).
inline double lame_mu(const Material& m) { return m.young / (2.0 * (1.0 + m.poisson)); }
inline double lame_lambda(const Material& m) {
  return m.young * m.poisson / ((1.0 + m.poisson) * (1.0 - 2.0 * m.poisson));
}

// One body, compiled from its rest mesh (double precision, body-local node indices).
struct BodyModel {
  std::string name;
  Material material;
  std::vector<Vec3d> rest;  // rest positions, also the initial positions
  std::vector<Tet> tets;
  std::vector<Tri> surface;          // outward boundary triangles
  std::vector<double> mass;          // lumped: density * volume / 4 from every tetrahedron
  std::vector<Mat3d> dm_inv;         // per tet: inverse rest edge matrix [X1-X0 X2-X0 X3-X0]^-1
  std::vector<double> volume;        // per tet: rest volume
  std::vector<std::uint8_t> pinned;  // per node: 1 = fixed in place (Dirichlet)
  Vec3d velocity;                    // initial velocity of the free nodes
};

// Throws std::runtime_error naming `name` and the problem (bad material, inverted element,
// unused node, wrong pinned size).
BodyModel compile_body(const TetMesh& mesh, const Material& material,
                       const std::vector<std::uint8_t>& pinned = {},
                       const std::string& name = "body");

// Pinned flags for the nodes whose rest position satisfies pred.
template <class Pred>
std::vector<std::uint8_t> pin_nodes(const TetMesh& mesh, Pred pred) {
  std::vector<std::uint8_t> p(mesh.x.size(), 0);
  for (std::size_t i = 0; i < p.size(); ++i) p[i] = pred(mesh.x[i]) ? 1 : 0;
  return p;
}

struct FemSettings {
  Vec3d gravity{0.0, -9.81, 0.0};  // m/s^2
  bool box = false;                // keep nodes inside the axis-aligned box (the tank)
  Vec3d box_lo, box_hi;            // m, the tank's inner faces
  double friction = 0.5;           // Coulomb coefficient of nodes sliding on the box
  double cg_tolerance = 1e-3;      // relative preconditioned residual that ends the solve
  int cg_max_iterations = 200;
  // A coarse level beside block Jacobi in the CG (fem/coarse.h, CPU backend): aggregates of
  // about 4 rest edges moving rigidly. Iterations stop growing with the stiffness.
  bool two_level = false;
  // The coarse level's largest size (6 unknowns a patch), which keeps its sparse factor small
  // (under 52 MB even were it dense); a larger body gets larger patches.
  static constexpr int kCoarseMaxSize = 1800;
  int rotation_iterations = 3;  // Mueller et al. 2016 iterations per step (warm-started)
  // Linearisations per step: 1 is the linearly implicit step; each further one re-extracts
  // the rotations at the newest end-of-step prediction and solves for the correction
  // (Newton on the backward Euler equations), at the cost of one more CG solve.
  int newton_iterations = 1;
};

// All bodies of a simulation, concatenated; arrays in solver precision (Real).
struct BodiesModel {
  FemSettings settings;
  std::vector<BodyModel> bodies;
  std::vector<int> node_offset, tet_offset, tri_offset;  // per body, and the totals last

  int nodes = 0, elements = 0;
  std::vector<Vec3> x0, v0;              // initial positions and velocities
  std::vector<Tet> tets;                 // global node indices
  std::vector<Tri> surface;              // global node indices
  std::vector<Vec3> grad;                // 3 per tet: rows of Dm^-1 (gradients of N1..N3)
  std::vector<Real> mu_vol, lambda_vol;  // per tet: V mu, V lambda
  std::vector<Real> beta;                // per tet: Rayleigh stiffness damping
  std::vector<Real> mass, alpha;         // per node: lumped mass, Rayleigh mass damping
  std::vector<std::uint8_t> pinned;      // per node
  // Gather lists: the elements around node i are inc[inc_start[i] .. inc_start[i+1]), each
  // tet * 4 + local index, so per-node sums need no atomics and are deterministic.
  std::vector<int> inc_start, inc;
};

// Throws std::runtime_error for inconsistent settings (no bodies, box without extent, bad
// tolerance).
BodiesModel compile_bodies(std::vector<BodyModel> bodies, const FemSettings& settings);

}  // namespace sphfem
