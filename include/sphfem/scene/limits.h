// What a scene would need, counted from the spec alone before anything is allocated: particles,
// tank wall samples, grid cells, tetrahedra, frames and memory. Each has a cap (documented in
// docs/scene-format.md, "Limits"), and the memory must fit what the machine has free, so that a
// typo in a particle radius is refused at once instead of allocating for minutes.
#pragma once

#include <cstdint>
#include <string>

#include "sphfem/scene/spec.h"

namespace sphfem {

inline constexpr double kMaxParticles = 200e6;      // fluid particles, emitters' included
inline constexpr double kMaxWallSamples = 200e6;    // frozen samples of the tank's walls
inline constexpr double kMaxGridCells = 268435456;  // 2^28 neighbour-grid cells
inline constexpr double kMaxFrames = 1e6;           // frames of one run

// Counts as doubles: a hostile scene's numbers must not overflow before they are compared.
struct SceneSize {
  double particles = 0;     // in the blocks at the start
  double capacity = 0;      // the solver's reservation: blocks, emitters, fluid.max_particles
  double emitted = 0;       // what the emitters add over the run
  double wall_samples = 0;  // tank wall samples
  double grid_cells = 0;
  double body_nodes = 0;  // generated shapes; a mesh file's size is known only once read
  double body_tets = 0;
  double frames = 0;                       // frames the run writes, the first at t = 0 included
  double fluid_bytes = 0, body_bytes = 0;  // fluid_bytes: the coupling's per particle too
  double bytes() const { return fluid_bytes + body_bytes; }
};

// Frames a run of `duration` seconds at `fps` writes: floor(duration * fps) + 1.
double frame_count(double duration, double fps);

// The bytes the fluid solver holds for `capacity` particles, the wall samples and the grid
// (the buffers of src/sph/fluid_buffers.h and sample_set.h; dfsph: with the kernel factors),
// and the FEM solver for a body.
double fluid_bytes(double capacity, double wall_samples, double grid_cells, bool dfsph);
// The ray coupling's buffers (couple/ray_coupling.h, couple/coupler.h) for `capacity`
// particles and at most `contacts` contacts a step; `solids`: closed obstacles in the
// near-surface density.
double coupling_bytes(double capacity, double contacts, bool solids);
// Contacts a step can have against the tank's faces: the particles next to them.
double contact_bound(const SceneSize& z);
// What the bodies of a run hold for their nodes, tetrahedra and surface triangles: the FEM
// solver's buffers and the model it shares with the simulation; with `contact` (fem.contact)
// the surface contact's trees and lists and the step's saved state; with `fluid` the ray
// coupling's and the leak check's trees over the surfaces.
double body_bytes(double nodes, double tets, double surface_triangles, bool contact, bool fluid);

// Counts the scene from its fields; cheap whatever the numbers (no lattice is built).
SceneSize scene_size(const SceneSpec& scene);

// Memory this process may still allocate: MemAvailable, lowered by a cgroup's memory.max.
double available_memory_bytes();

// Throws SceneError naming the file, the field that drives the count and the fix when a count
// passes its cap or the memory passes `available_bytes`.
void check_limits(const SceneSpec& scene, const std::string& file, double available_bytes);

// The frame cap for a run whose duration is given apart from the scene (run --duration).
void check_frame_limit(double duration, double fps, const std::string& file,
                       const std::string& field);

}  // namespace sphfem
