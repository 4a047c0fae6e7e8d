// Counting a scene before it is built (scene/limits.h): the same lattices as compile_fluid and
// the body generators, counted in doubles instead of filled, and checked against the caps.
#include "sphfem/scene/limits.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "scene/messages.h"
#include "sphfem/scene/bodies.h"
#include "sphfem/scene/fields.h"

namespace sphfem {
namespace {

using namespace scene_text;

constexpr double kPi = 3.14159265358979323846;

// Lattice points along one axis inside [lo, hi] at spacing d, as compile_fluid places them.
double inner_points(double extent, double d) {
  return std::max(1.0, std::floor(extent / d + 1e-6));
}

// Particles of all emitters over the run: the volume they pour, one particle per d^3, plus a
// disc of slack per emitter for the layer in flight (the lattice holds rho0 at one per d^3).
double emitted_particles(const SceneSpec& s, double d) {
  double n = 0;
  for (const EmitterSpec& e : s.fluid.emitters) {
    const double active = std::max(0.0, std::min(e.end, s.simulation.duration) - e.start);
    const double disc = kPi * (e.radius / d) * (e.radius / d) + 4.0 * e.radius / d + 1.0;
    n += e.speed * active * kPi * e.radius * e.radius / (d * d * d) + 2.0 * disc;
  }
  return n;
}

std::string count(double n) {
  char buf[64];
  if (!std::isfinite(n)) return "more than 1e308";
  if (n < 1e9)
    std::snprintf(buf, sizeof buf, "%.0f", n);
  else
    std::snprintf(buf, sizeof buf, "%.3g", n);
  return buf;
}

std::string gib(double bytes) {
  char buf[64];
  if (bytes < 1024.0 * 1024.0 * 1024.0)
    std::snprintf(buf, sizeof buf, "%.0f MiB", bytes / (1024.0 * 1024.0));
  else
    std::snprintf(buf, sizeof buf, "%.3g GiB", bytes / (1024.0 * 1024.0 * 1024.0));
  return buf;
}

// x rounded up to three significant digits, for the numbers a fix suggests.
std::string up3(double x) {
  if (!(x > 0) || !std::isfinite(x)) return num(x);
  const double unit = std::pow(10.0, std::floor(std::log10(x)) - 2);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", std::ceil(x / unit) * unit);
  return buf;
}

// The particle radius at which `n` particles (scaling as r^-3) come down to `target`.
std::string radius_for(const SceneSpec& s, double n, double target) {
  return up3(s.fluid.particle_radius * std::cbrt(n / target));
}

// A number read from a one-line file such as cgroup v2's memory.max; "max" or absent: none.
double read_bytes(const char* path) {
  std::ifstream in(path);
  std::string word;
  if (!(in >> word) || word == "max") return -1;
  try {
    return std::stod(word);
  } catch (...) { return -1; }
}

}  // namespace

// The small tables a fluid run holds whatever its size (kernel tables, the tank's faces and
// their trees, per-thread sums).
constexpr double kFixedBytes = 1 << 20;

double frame_count(double duration, double fps) { return std::floor(duration * fps) + 1.0; }

double contact_bound(const SceneSize& z) {
  // A particle moves less than a spacing in a step, so only the layer next to a face can hit
  // it: about one particle per sample of one of the walls' two layers. (Bodies' and obstacles'
  // faces are left out: their areas are known only once their meshes are read.)
  return std::min(z.capacity, 0.5 * z.wall_samples);
}

double fluid_bytes(double capacity, double wall_samples, double grid_cells, bool dfsph) {
  // Per particle: x, v, a, tmp (4 x 12 B); rho, p, two warm starts, tmp (5 x 4 B), and under
  // DFSPH alpha, kappa, kappa_sum (3 x 4 B); nb, flags, nbr_n, nbr_at, id, keys, perm (7 x 4 B);
  // the neighbour lists: under WCSPH room for about twice the 33 lattice points within the support
  // (the compiled count is 27 or 33 as the support rounds; the larger is taken), rounded down to a
  // multiple of eight (64 x 4 B); under DFSPH packed in a pool an eighth longer than they are, 36
  // entries a particle (31.5 measured in the dam break and in a tank: fluid neighbours padded
  // to eight, the tank's samples by the walls) of 4 B, with the pairs' kernel factors beside
  // them (4 B more); the radix sort's scratch, grown by a quarter (10 B); the initial x0, v0
  // in the scene's model (24 B); under DFSPH the divergence warm start's fluid pairs (12 B),
  // under WCSPH the forces' records of a neighbour (8 x 4 B).
  // Per wall sample: x (12 B), nine reals and two ints (44 B), x and psi in the scene's model
  // (16 B). Per cell: the fluid's and the samples' cell starts (8 B). Under DFSPH the host lists
  // the fluid neighbours of the samples with fluid in reach (WallLists): at most about 0.3 of them
  // a particle (0.27 measured in a half-filled tank, 0.11 in the dam break), each about 10 entries
  // in a pool a quarter longer, and its place and block (62 B).
  const double lists = dfsph ? 36.0 * 8.0 + 12.0 + 3 * 4.0 : 64.0 * 4.0 + 8 * 4.0;
  const double wall_lists = dfsph ? std::min(wall_samples, 0.3 * capacity) * 62.0 : 0.0;
  return capacity * (4 * 12.0 + 5 * 4.0 + 7 * 4.0 + lists + 10.0 + 24.0) +
         wall_samples * (56.0 + 16.0) + wall_lists + grid_cells * 8.0 + kFixedBytes;
}

double coupling_bytes(double capacity, double contacts, bool solids) {
  // Per particle, grown by a quarter as the buffers of the ray coupling are: its hits against
  // the bodies and the static set, the near-surface closest points, the exact crossing test's
  // scratch (4 ints, 14 reals, 5 vectors: 132 B) and the coupler's travel limits (16 B); with
  // closed obstacles, their closest points (2 ints, 3 reals, a vector: 32 B). Per contact of
  // the exchange: its record (128 B) and three node entries of four words (48 B).
  return 1.25 * (capacity * (132.0 + 16.0 + (solids ? 32.0 : 0.0)) + contacts * 176.0);
}

double body_bytes(double nodes, double tets, double surface_triangles, bool contact, bool fluid) {
  // Per node, 281 B: the solver's x, v, external force and eleven CG and step vectors
  // (14 x 12 B), preconditioner block (24 B), mass, damping, zero damping, gather start
  // (16 B), pinned, wall mask and zero flags (3 B); the model's x0, v0, mass, damping, gather
  // start, pinned (37 B) and its per-body rest position, mass and pinned in double (33 B).
  // Per tet, 372 B: the solver's nodes, gradients, moduli, gather entries (80 B), rotated
  // gradients, element forces, rotations and their scratch (116 B); the model's same 80 B
  // and its per-body nodes, inverse edge matrix and volume in double (96 B). Per surface
  // triangle 36 B: its nodes in the solver, the model and the body.
  // Surface contact: x0, reference and saved positions, the saved step's v, dv and impulses,
  // body, inverse mass, rest height, flags and the starts of its surface neighbours, faces
  // and elements per node (105 B); per tet the saved rotations (16 B) and the volume floor's
  // copy of its nodes, rest volume, floor, flag and node-to-element entries (41 B); per triangle
  // the faces' edges, tree, leaves, query lists, near list and the surface graph's entries (216 B).
  // With fluid: the coupling's and the leak check's trees (80 B a triangle) and node positions (16
  // B).
  const double per_node = 281.0 + (contact ? 105.0 : 0.0) + (fluid ? 16.0 : 0.0);
  const double per_tet = 372.0 + (contact ? 57.0 : 0.0);
  const double per_tri = 36.0 + (contact ? 216.0 : 0.0) + (fluid ? 80.0 : 0.0);
  // The small tables of a run with bodies, whatever their size (per-thread pair lists, the
  // energy meter's sums).
  constexpr double kFixed = 64 << 10;
  if (!(nodes > 0)) return 0.0;
  return nodes * per_node + tets * per_tet + surface_triangles * per_tri + kFixed;
}

SceneSize scene_size(const SceneSpec& s) {
  SceneSize z;
  z.frames = frame_count(s.simulation.duration, s.output.fps);
  if (s.has_fluid()) {
    const double d = 2.0 * s.fluid.particle_radius;
    for (const FluidBlockSpec& b : s.fluid.blocks)
      z.particles += inner_points(b.hi.x - b.lo.x, d) * inner_points(b.hi.y - b.lo.y, d) *
                     inner_points(b.hi.z - b.lo.z, d);
    z.emitted = emitted_particles(s, d);
    z.capacity = s.fluid.max_particles > 0 ? std::max(z.particles, double(s.fluid.max_particles))
                                           : z.particles + z.emitted;
    // Tank walls and grid as compile_fluid lays them: kernel support h = 2 d, so 2 layers.
    const double h = 2.0 * d, layers = 2.0, pad = layers * d + h;
    double all = 1, inner = 1;
    z.grid_cells = 1;
    for (int k = 0; k < 3; ++k) {
      const double extent = s.domain.hi[k] - s.domain.lo[k];
      const double in = inner_points(extent, d);
      const double walls = (k == 1 && s.domain.open_top) ? layers : 2.0 * layers;
      all *= in + walls;
      inner *= in;
      z.grid_cells *= std::ceil((extent + 2.0 * pad) / h);
    }
    z.wall_samples = all - inner;
    z.fluid_bytes = fluid_bytes(z.capacity, z.wall_samples, z.grid_cells,
                                s.simulation.solver == SolverKind::DFSPH);
    // The ray coupling runs with bodies, the tank's faces in the rays, or obstacles.
    const bool rays = s.coupling.method == CouplingMethod::RayTraced;
    if (rays && (!s.bodies.empty() || s.coupling.tank_rays || !s.obstacles.empty()))
      z.fluid_bytes += coupling_bytes(z.capacity, contact_bound(z), !s.obstacles.empty());
  }
  for (const BodySpec& b : s.bodies) {
    const ShapeSize shape = shape_size(b);
    z.body_nodes += shape.nodes;
    z.body_tets += shape.tets;
  }
  // A closed surface of V vertices has 2 V - 4 triangles (2 V per hole through it), and a
  // body's surface vertices are some of its nodes.
  z.body_bytes =
      body_bytes(z.body_nodes, z.body_tets, 2.0 * z.body_nodes, s.fem.contact, s.has_fluid());
  if (s.fem.preconditioner == FemPreconditioner::TwoLevel) {
    // The coarse level: a patch of at least 16 nodes, 6 unknowns each, its sparse matrix and
    // factor bounded by two dense matrices of doubles, capped; per node its patch, position
    // and mask.
    const double size = std::min(double(FemSettings::kCoarseMaxSize), 6.0 * z.body_nodes / 16.0);
    z.body_bytes += 16.0 * size * size + 17.0 * z.body_nodes;
  }
  return z;
}

double available_memory_bytes() {
  double avail = -1;
  std::ifstream in("/proc/meminfo");
  std::string key, unit;
  double kib = 0;
  while (in >> key >> kib) {
    std::getline(in, unit);
    if (key == "MemAvailable:") {
      avail = kib * 1024.0;
      break;
    }
  }
  if (avail < 0) avail = double(sysconf(_SC_AVPHYS_PAGES)) * double(sysconf(_SC_PAGESIZE));
  // A container's limit can be far below the machine's free memory.
  const double limit = read_bytes("/sys/fs/cgroup/memory.max");
  const double used = read_bytes("/sys/fs/cgroup/memory.current");
  if (limit > 0) avail = std::min(avail, std::max(0.0, limit - std::max(0.0, used)));
  return avail;
}

void check_frame_limit(double duration, double fps, const std::string& file,
                       const std::string& field) {
  const double frames = frame_count(duration, fps);
  if (frames > kMaxFrames)
    fail(file, field,
         "the run would write " + count(frames) + " frames (" + num(duration) + " s at " +
             num(fps) + " frames/s), more than the limit of " + count(kMaxFrames),
         "shorten the duration to at most " + num(std::floor((kMaxFrames - 1) / fps)) +
             " s or lower output.fps");
}

void check_limits(const SceneSpec& s, const std::string& file, double available_bytes) {
  check_frame_limit(s.simulation.duration, s.output.fps, file, "simulation.duration");
  const SceneSize z = scene_size(s);
  const std::string need = " (about " + gib(z.bytes()) + ")";
  if (s.has_fluid()) {
    if (z.capacity > kMaxParticles) {
      const std::string what = "the scene would need " + count(z.capacity) + " particles" + need +
                               ", more than the limit of " + count(kMaxParticles);
      if (s.fluid.max_particles > 0 && double(s.fluid.max_particles) >= z.particles)
        fail(file, "fluid.max_particles", what,
             "set max_particles to at most " + count(kMaxParticles));
      if (z.particles >= z.emitted)
        fail(file, "fluid.particle_radius", what + " in fluid.blocks",
             "set particle_radius to at least " + radius_for(s, z.capacity, kMaxParticles) +
                 " m or make the blocks smaller");
      fail(file, "fluid.emitters", what + " from the emitters over the run",
           "set fluid.particle_radius to at least " + radius_for(s, z.capacity, kMaxParticles) +
               " m, end the emitters sooner (end) or shorten simulation.duration");
    }
    if (z.grid_cells > kMaxGridCells)
      fail(file, "fluid.particle_radius",
           "the neighbour grid over the domain would have " + count(z.grid_cells) +
               " cells (cell size 4 * particle_radius)" + need + ", more than the limit of " +
               count(kMaxGridCells),
           "set particle_radius to at least " + radius_for(s, z.grid_cells, kMaxGridCells) +
               " m or make the domain smaller");
    if (z.wall_samples > kMaxWallSamples)
      fail(file, "fluid.particle_radius",
           "the tank's walls would need " + count(z.wall_samples) + " samples" + need +
               ", more than the limit of " + count(kMaxWallSamples),
           "set particle_radius to at least " +
               up3(s.fluid.particle_radius * std::sqrt(z.wall_samples / kMaxWallSamples)) +
               " m or make the domain smaller");
  }
  // A shape past its own cap is named by check_bodies, with the resolution that fits.
  for (const BodySpec& b : s.bodies)
    if (shape_size(b).tets > scene::kMaxBodyTets) return;
  if (z.bytes() > available_bytes) {
    const bool fluid = z.fluid_bytes >= z.body_bytes;
    const std::string what =
        "the scene would need about " + gib(z.bytes()) + " of memory (" + count(z.capacity) +
        " particles, " + count(z.wall_samples) + " wall samples, " + count(z.body_tets) +
        " tetrahedra), more than the " + gib(available_bytes) + " free on this machine";
    if (fluid)
      fail(file, "fluid.particle_radius", what,
           "set particle_radius to at least " +
               radius_for(s, z.fluid_bytes, std::max(1.0, available_bytes - z.body_bytes)) +
               " m, make the fluid smaller or free memory");
    std::size_t biggest = 0;
    for (std::size_t i = 1; i < s.bodies.size(); ++i)
      if (shape_size(s.bodies[i]).tets > shape_size(s.bodies[biggest]).tets) biggest = i;
    fail(file, indexed("bodies", biggest) + ".resolution", what,
         "lower the bodies' resolution or free memory");
  }
}

}  // namespace sphfem
