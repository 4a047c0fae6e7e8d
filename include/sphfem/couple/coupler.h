// Ray-traced two-way coupling of the fluid with triangle surfaces (paper §3.3 and §4): the
// travel fractions that keep particles from crossing a surface (eq. 6), and the per-face
// momentum exchange (impulse.h) between the particles whose rays hit a face and its nodes.
//
// Where it runs, in a fluid step with a StepHook (sph/solver.h):
//   kick (v*) -> before_drift: bodies step over the same dt, BVH refit, one ray per particle
//   along its velocity relative to the surface -> Coupler::travel -> drift limited by it ->
//   after_drift: Coupler::apply (-J to the particles now, +J into the nodes' impulse array,
//   which the body solver adds to its next step's right-hand side).
// Hits are grouped by face as in paper §4.3: (face, particle) pairs radix-sorted by face, run
// starts by a scan, then one thread per face, so particle velocities are written without
// atomics; node impulses (a node is shared by several faces) are listed per face and summed
// node by node in a fixed order, so a run gives the same bits on any thread count.
//
// Why impulses into the next body step rather than v += J / m on the nodes now: for linear
// elasticity both lead to the same linear system of the implicit step (only the rotations
// would be taken at a prediction that includes the kick), so the choice is about ownership:
// the body solver keeps its state and warm starts to itself and treats pinned nodes in one
// place, and the next step's rays see the answer either way. The body gains J up to the sum
// of its CG residual (pinned nodes excepted).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "sphfem/core/backend.h"
#include "sphfem/core/memory.h"
#include "sphfem/couple/impulse.h"
#include "sphfem/fem/mesh.h"
#include "sphfem/sph/solver.h"

namespace sphfem {

struct BodyArrays;
struct BodiesModel;

// Hits of one batch of rays, one entry per fluid particle (in the current particle order), in
// the coupler's memory space. face = -1: no hit. The ray starts at the particle and runs along
// v - v_s, v_s the velocity of the surface at the hit; t is the distance along it (m); the hit
// point has weights (1 - u - v, u, v) on the triangle's nodes v[0], v[1], v[2].
struct HitArrays {
  MemSpace space = MemSpace::Host;
  const int* face = nullptr;
  const Real* t = nullptr;
  const Real* u = nullptr;
  const Real* v = nullptr;
  // Optional, per particle: a contact that keeps a separation speed rather than obeying the
  // restitution and slip law. Finite bias b: the contact holds the normal relative velocity
  // at b (the particle leaving the face at b m/s, or faster) with a normal impulse that never
  // pulls; NaN: the law. (The near-surface pressure's push, couple/ray_coupling.h.)
  const Real* bias = nullptr;
};

// One set of triangles the hits index, with its nodes, in the coupler's memory space. The
// sets passed to a call are numbered one after another: set k's triangle i is face
// (triangles of sets 0..k-1) + i, which must be the ray caster's numbering. A static collider
// has mass = nullptr (infinite), v = nullptr (at rest) and impulse = nullptr.
struct CoupleSurface {
  MemSpace space = MemSpace::Host;
  int nodes = 0, triangles = 0;
  const Tri* tri = nullptr;  // node indices into x, v, mass, pinned, impulse
  const Vec3* x = nullptr;
  const Vec3* v = nullptr;
  const Real* mass = nullptr;
  const std::uint8_t* pinned = nullptr;  // nullptr: none; pinned nodes have infinite mass
  Vec3* impulse = nullptr;               // N s per node, added to (never cleared here)
  // Host memory: body b owns triangles [tri_offset[b], tri_offset[b + 1]) (empty: one body
  // owning all), and meets the fluid with coeffs[b].
  std::vector<int> tri_offset;
  std::vector<ContactCoeffs> coeffs;
};

// The FEM bodies' surfaces (BodyArrays from BodySolver::arrays, body ranges from the model),
// one ContactCoeffs per body.
CoupleSurface body_surface(const BodyArrays& arrays, const BodiesModel& model,
                           std::vector<ContactCoeffs> coeffs);
// A static triangle mesh (tank, obstacle): infinite mass, at rest.
CoupleSurface static_surface(MemSpace space, int nodes, const Vec3* x, int triangles,
                             const Tri* tri, ContactCoeffs coeffs);

// The bodies' response to impulses over a step, for the joint solve (optional): q = A p and
// A's 3x3 diagonal blocks (xx, yy, zz, xy, xz, yz), over the first nodes() nodes of the
// surface sets' numbering, in the coupler's memory space; 0 rows on pinned nodes. With it the
// solve's node matrix is A in place of the lumped masses M (src/couple/contact_solve.h), and
// its outcome reaches those nodes as the velocity change dV = A^-1 W J (add_velocity) instead
// of impulses: the response the solve promised the particles, whatever the next step's dt
// (impulses into a next step of smaller dt, a softer A, shot light nodes off at 17 m/s).
class NodeOperator {
 public:
  virtual ~NodeOperator() = default;
  virtual int nodes() const = 0;
  virtual void apply(const Vec3* p, Vec3* q) = 0;
  virtual void diagonal(Real* blocks) = 0;
  virtual void add_velocity(const Vec3* dv) = 0;
};

struct CoupleStats {
  int contacts = 0;     // particles with a hit
  int faces = 0;        // distinct faces hit
  int exchanges = 0;    // contacts that exchanged an impulse
  int rounds = 0;       // active-set rounds of the joint solve
  int iterations = 0;   // its conjugate-gradient iterations, all rounds
  double residual = 0;  // m/s, the largest contact's distance from its law at the end
  // Impulse given to each body (N s), the bodies of all sets in order; the particles received
  // the opposite in total.
  std::vector<Vec3d> body_impulse;
};

class Coupler {
 public:
  static constexpr int kMaxSurfaces = 4;  // sets per call

  virtual ~Coupler() = default;

  // Eq. 6 per particle: travel = max(0, t - skin) / |v - v_s| dt (clamped to [0, 1], 1 without
  // a hit) and s = v_s, for FluidSolver's drift. The arrays belong to the coupler and stay
  // valid until its next call.
  virtual DriftLimits travel(const HitArrays& hits, const FluidArrays& fluid,
                             const std::vector<CoupleSurface>& surfaces, Real skin, double dt) = 0;

  // After the drift, before apply: particles with a hit end at least skin in front of the
  // face's plane, on the side they came from (eq. 6 keeps the skin only along the ray).
  virtual void push_out(const HitArrays& hits, const FluidArrays& fluid,
                        const std::vector<CoupleSurface>& surfaces, Real skin) = 0;

  // The momentum exchange, every contact of the call solved together (src/couple/
  // contact_solve.h): each particle with a hit gets -J_c (fluid.v changes), the face's nodes
  // +J_c by the barycentric weights of its hit (added to impulse), so that every contact meets
  // its restitution and slip law at once. Which side a particle is on is taken from its
  // position against the face's plane, so call it after the drift. `bodies`: the bodies'
  // step operator (null: free nodes of their lumped masses).
  virtual CoupleStats apply(const HitArrays& hits, const FluidArrays& fluid,
                            const std::vector<CoupleSurface>& surfaces,
                            NodeOperator* bodies = nullptr) = 0;
};

// Throws std::runtime_error when the backend is not usable here (e.g. CUDA without a GPU).
std::unique_ptr<Coupler> make_coupler(Backend backend);

}  // namespace sphfem
