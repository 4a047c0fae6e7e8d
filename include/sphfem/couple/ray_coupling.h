// The paper's ray-traced two-way coupling, as the coupling stages of Simulation::step
// (core/profile.h): after the bodies took the fluid's dt, their surface BVH is refit over the
// step, every particle casts one ray along its motion relative to the surfaces (bodies and,
// optionally, the tank's faces as static colliders), the drift stops a skin short of the
// nearest hit (eq. 6), and after the drift the Coupler exchanges impulses per face. An exact test
// of each particle's actual path against every body face moving linearly over the step finds the
// particles that met a surface anyway (another face than the nearest one, or a face that turned
// within the step), puts them a skin in front of it and counts what still meets one (`crossed`), so
// leakage is measured every step rather than assumed away.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "sphfem/core/backend.h"
#include "sphfem/couple/impulse.h"
#include "sphfem/fem/solver.h"
#include "sphfem/sph/solver.h"

namespace sphfem {

// The bodies' step failed (non-finite solve); the runner reports it.
struct BodyStepError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct RayCouplingSettings {
  // false: the boundary-particle baseline (paper Fig. 8). The hook then casts no ray and
  // exchanges no impulse: it steps the bodies, hands their surface to the fluid's samples
  // (StepHook::moving_boundary), whose forces return to the nodes, and still measures every
  // particle's crossing of a body surface (`crossed`) without putting it back.
  bool rays = true;
  // Near-surface density (sph/surface_density.h): each particle's closest body surface point
  // within `support` (the kernel's radius) goes to the fluid, and the pressure it exerts
  // there returns to the face's nodes. The closed obstacles' faces count as surfaces too (of
  // infinite mass: nothing returns).
  bool near_surface = false;
  // The joint exchange meets the bodies through their step operator (Coupler::apply's
  // NodeOperator) rather than their lumped node masses.
  bool implicit_exchange = false;
  Real support = 0;
  Real skin = 0;  // m, kept between a particle and the surface it hits
  bool tank = true;
  Vec3 tank_lo, tank_hi;  // the tank's inner faces
  bool open_top = false;  // no lid among the tank's faces
  ContactCoeffs wall;
  std::vector<ContactCoeffs> body;  // one per body of the BodySolver's model
  // Obstacles, ray-cast with the tank's faces (rays on): their vertices (where they start),
  // triangles, each obstacle's range of triangles and its coefficients.
  std::vector<Vec3> obstacle_x;
  std::vector<Tri> obstacle_tris;
  std::vector<int> obstacle_offset;
  std::vector<ContactCoeffs> obstacle_coeffs;
  std::vector<std::uint8_t> obstacle_closed;  // per obstacle: bounds a solid, faces outward
  double rebuild_quality = 2.0;               // rebuild the bodies' BVH above this quality ratio
};

// Sums since the last reset_stats().
struct RayCouplingStats {
  long steps = 0;
  long contacts = 0;   // particle-face hits that went to the coupler
  long crossed = 0;    // particles whose displacement crossed a body surface (goal: 0)
  long corrected = 0;  // contacts found after the drift and put back in front of the face
  long joint_rounds = 0, joint_iterations = 0;  // the joint exchange's active-set rounds, CG
  int rebuilds = 0;
  long near_surface = 0;     // particle-steps with a body surface within the kernel's support
  double ms_leak_check = 0;  // the exact test's first pass (a part of contact_fix)
  std::vector<Vec3d> body_impulse;  // N s given to each body by the fluid
};

// Not the owner of the bodies: Simulation steps them between pressure() and cast().
class RayCoupling : public SurfaceQuery {
 public:
  // The stages, in the order Simulation::step calls them; each finishes its work before it
  // returns. proximity() and moving_boundary() (SurfaceQuery) come first.
  // The pressure the near-surface density gave the particles, back to the faces' nodes; what
  // the fluid gave each body since its last step goes to the stats; the nodes' positions are
  // remembered as the start of the bodies' step.
  virtual void before_bodies(const FluidArrays& fluid) = 0;
  // After the bodies' step: BVH refit over it, the rays, and each particle's travel fraction
  // (the baseline: only what the leak check needs).
  virtual DriftLimits cast(const FluidArrays& fluid, double dt) = 0;
  // After the drift: particles pushed a skin in front of the faces they hit, then the exact
  // contact test of every path against the moving faces and its fix (counts `crossed`).
  virtual void fix_contacts(const FluidArrays& fluid) = 0;
  // The per-face momentum exchange: -J to the particles now, +J into the nodes' impulses.
  virtual void exchange(const FluidArrays& fluid) = 0;

  // The bodies were moved outside a step (a state was loaded): the BVH is built again over
  // where they are now.
  virtual void bodies_moved() = 0;
  // Before cast(): the obstacles' vertices (RayCouplingSettings::obstacle_x order) at the
  // start and the end of this step, dt apart, for obstacles on a path. From then on their
  // faces move linearly over each step, at that velocity, in the rays, the exchange and the
  // exact crossing test. Without tank faces or obstacles in the ray cast it does nothing.
  virtual void move_obstacles(const std::vector<Vec3>& x_start, const std::vector<Vec3>& x_end,
                              double dt) = 0;

  virtual const RayCouplingStats& stats() const = 0;
  virtual void reset_stats() = 0;
};

// bodies may be null (tank faces only). Throws std::runtime_error when the backend is not
// usable here.
std::unique_ptr<RayCoupling> make_ray_coupling(const RayCouplingSettings& settings,
                                               BodySolver* bodies, Backend backend);

}  // namespace sphfem
