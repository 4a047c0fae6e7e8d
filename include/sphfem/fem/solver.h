// The deformable-body solver behind one interface for every backend: co-rotated linear FEM
// on tetrahedra (paper eq. 5), implicit Euler solved matrix-free by preconditioned CG.
// The physics is written once in src/fem/stages.h (derivation of the step there) and
// instantiated for the CPU (solver_cpu.cpp) and CUDA (solver_cuda.cu).
//
// Known limitation: the step linearises with the warped stiffness R K_e R^T (rotations held
// fixed), which omits the derivative of R with respect to the positions. Two consequences
// show under large deformation or large steps: (1) a strongly crushed body gains some spin
// while it springs back (measured: a sphere flattened to a plane recovers with ~0.9 rad/s,
// one squashed by 20 % with ~0.04 rad/s; quadratic in the deformation, not in dt;
// FemSettings::newton_iterations = 5 roughly halves it); (2) a slender body under tension
// lacks the stabilising stiffness of that tension, so quasi-static steps far above its
// lowest period can diverge laterally. Dynamic steps with dt near the fluid's are
// unaffected. The remedy is the rotation-derivative term of the co-rotated Hessian (McAdams
// et al. 2011), projected to stay positive semi-definite.
#pragma once

#include <memory>
#include <vector>

#include "sphfem/core/backend.h"
#include "sphfem/core/memory.h"
#include "sphfem/fem/model.h"
#include "sphfem/fem/state.h"

namespace sphfem {

struct BodySnapshot {
  int n = 0;
  std::vector<Vec3> x, v;  // all bodies' nodes, in model order (see BodiesModel offsets)
};

struct BodyStepInfo {
  int cg_iterations = 0;
  double cg_residual = 0;  // preconditioned residual norm relative to the right-hand side
  int contacts = 0;        // nodes the box pushed back after the step (a last resort)
  int held = 0;            // nodes the tank's walls held inside the step's solve
};

struct BodyProfile {
  double ms_rotations = 0, ms_assemble = 0, ms_solve = 0, ms_integrate = 0;
  long steps = 0, cg_iterations = 0;
  double ms_total() const { return ms_rotations + ms_assemble + ms_solve + ms_integrate; }
};

// The solver's node arrays in the backend's memory space (device pointers under CUDA), for
// coupling kernels that run on the same backend. impulse (N s) is added into the next step's
// right-hand side and then cleared; pinned nodes ignore it.
struct BodyArrays {
  MemSpace space = MemSpace::Host;
  int nodes = 0, triangles = 0;
  Vec3* x = nullptr;
  Vec3* v = nullptr;
  Vec3* impulse = nullptr;
  const Real* mass = nullptr;
  const std::uint8_t* pinned = nullptr;
  const Tri* surface = nullptr;
};

class BodySolver {
 public:
  virtual ~BodySolver() = default;
  virtual const BodiesModel& model() const = 0;
  virtual int node_count() const = 0;
  virtual double time() const = 0;
  virtual long steps() const = 0;

  // One implicit Euler step of dt seconds: rotations, assembly, CG solve, positions, box.
  virtual BodyStepInfo step(double dt) = 0;
  virtual void snapshot(BodySnapshot& out) = 0;

  // 1/2 sum m v^2, and the co-rotated elastic energy sum V (mu |eps|^2 + lambda/2 tr(eps)^2)
  // with rotations extracted from the current positions.
  virtual double kinetic_energy() = 0;
  virtual double elastic_energy() = 0;

  // Impulses (N s, one per node) added to the next step; calls accumulate.
  virtual void add_node_impulses(const std::vector<Vec3>& impulse) = 0;
  // External forces (N, one per node) applied in every step until replaced; empty = none.
  virtual void set_node_forces(const std::vector<Vec3>& force) = 0;

  // Overwrite the state (tests, scripted poses). set_positions re-extracts every element
  // rotation from scratch, so any pose is allowed, however far from the last.
  virtual void set_positions(const std::vector<Vec3>& x) = 0;
  virtual void set_velocities(const std::vector<Vec3>& v) = 0;
  // Positions and velocities of some nodes (an obstacle's projection), the rotations kept.
  virtual void set_nodes(const std::vector<int>& nodes, const std::vector<Vec3>& x,
                         const std::vector<Vec3>& v) = 0;
  // Elastic forces (N, one per node) at the current positions.
  virtual void elastic_forces(std::vector<Vec3>& f) = 0;

  // The state's exact image (fem/state.h); load() continues from it bit for bit and throws
  // std::invalid_argument for a state of another model.
  virtual void save(BodyState& out) const = 0;
  virtual void load(const BodyState& in) = 0;

  virtual BodyArrays arrays() = 0;

  // The body's response to an impulse J over the last step, dV = A^-1 J with
  // A = M + dt (dt + beta) K_R (the implicit step's operator with its rotations and dt, less
  // the mass-proportional damping, which would take momentum): q = A p over all nodes, 0 on
  // pinned ones; its 3x3 diagonal blocks (xx, yy, zz, xy, xz, yz per node); and the step's
  // share of dv on the free nodes, v += dv and x += dt dv (x_new - x_old = dt v_new stays
  // true, as the implicit step with the impulse in it would give). Arrays in the solver's
  // memory space. The coupling's joint solve meets the
  // body through them: a light node held by its elements is not a free one (docs/design.md).
  virtual void apply_step_operator(const Vec3* p, Vec3* q) = 0;
  virtual void step_operator_diagonal(Real* blocks) = 0;
  virtual void add_velocity_change(const Vec3* dv) = 0;
  // dt of the last step (0 before the first).
  virtual double last_dt() const = 0;
  virtual const BodyProfile& profile() const = 0;
  virtual void reset_profile() = 0;
};

// Throws std::runtime_error when the backend is not usable here (e.g. CUDA without a GPU).
// The solver keeps the model it is given (shared, not copied: a body's model is about half of
// what its run holds); the first form copies it.
std::unique_ptr<BodySolver> make_body_solver(const BodiesModel& model, Backend backend);
std::unique_ptr<BodySolver> make_body_solver(std::shared_ptr<const BodiesModel> model,
                                             Backend backend);

}  // namespace sphfem
