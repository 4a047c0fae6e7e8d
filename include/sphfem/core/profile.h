// The stages of one coupled step, named once: Simulation::step runs them in this order, each
// is timed into one StepProfile, and the `ms_*` gauge columns and `sphfem bench` print them.
//
//   neighbors    boundary samples placed, particles re-sorted by grid cell
//   proximity    each particle's closest body surface (near-surface density)
//   density      neighbour lists, density (DFSPH: its factors and warm starts)
//   divergence   DFSPH: the velocity field made divergence-free
//   forces       gravity, viscosity (WCSPH: pressure) -> kick
//   pressure     DFSPH: the density solve -> v*; the samples' and the near-surface pressure
//                impulses go to the body nodes
//   fem          the bodies' implicit step over the same dt
//   body_contact the bodies' nodes against the obstacles, and their surfaces against each
//                other and themselves
//   collide      BVH refit, one ray per particle along its motion relative to the surfaces
//   drift        x += dt v*, limited a skin short of the nearest hit (paper eq. 6)
//   contact_fix  exact contact test of each path against the moving faces, and its fix
//   exchange     per-face momentum exchange (paper §4)
//   emit         new particles from the emitters
#pragma once

namespace sphfem {

enum class Stage {
  Neighbors,
  Proximity,
  Density,
  Divergence,
  Forces,
  Pressure,
  Fem,
  BodyContact,
  Collide,
  Drift,
  ContactFix,
  Exchange,
  Emit,
  Count
};

// Lower-case name, as in the ms_<name> gauge columns.
const char* stage_name(Stage s);

// Wall-clock milliseconds per stage, summed over `steps` steps since the last clear().
struct StepProfile {
  double ms[int(Stage::Count)] = {};
  long steps = 0;
  void clear() { *this = StepProfile(); }
  double total() const {
    double t = 0;
    for (double v : ms) t += v;
    return t;
  }
};

}  // namespace sphfem
