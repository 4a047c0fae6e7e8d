// What a scene file says, in SI units, after loading and validation.
// JSON -> SceneSpec (this file) -> compiled fluid model (sph/model.h) and bodies model
// (fem/model.h), both made in scene/compile.h -> state.
#pragma once

#include <string>
#include <vector>

#include "sphfem/core/vec.h"
#include "sphfem/fem/model.h"
#include "sphfem/fem/tetrahedralize.h"
#include "sphfem/sph/solver_kind.h"

namespace sphfem {

enum class KernelKind { CubicSpline, WendlandC2 };

struct SimulationSpec {
  double duration = 1.0;  // s, simulated time
  double dt_min = 1e-6;   // s, below this the run stops as unstable
  double dt_max = 2e-3;   // s, upper bound of the adaptive step
  double cfl = 0.4;       // Courant number on the particle spacing
  SolverKind solver = SolverKind::DFSPH;
  Vec3d gravity{0.0, -9.81, 0.0};      // m/s^2
  double density_tolerance = 1e-3;     // DFSPH: mean relative density error target
  double divergence_tolerance = 1e-3;  // DFSPH: mean relative density change per step from div v
  int max_iterations = 100;            // DFSPH: cap on pressure iterations per solve
};

struct FluidBlockSpec {
  Vec3d lo, hi;    // m, box filled with particles on a cubic lattice
  Vec3d velocity;  // m/s, initial velocity
};

struct EmitterSpec {
  Vec3d position;                   // m, nozzle centre
  Vec3d direction{0.0, -1.0, 0.0};  // unit after loading
  double radius = 0.05;             // m, nozzle radius
  double speed = 1.0;               // m/s, outflow speed
  double start = 0.0;               // s
  double end = 1e30;                // s
};

struct FluidSpec {
  double particle_radius = 0.0125;    // m; lattice spacing is twice this
  double rest_density = 1000.0;       // kg/m^3
  double viscosity = 1e-6;            // m^2/s, physical kinematic viscosity
  double xsph = 0.0;                  // XSPH velocity smoothing factor, 0..1
  double artificial_viscosity = 0.0;  // Monaghan alpha, 0 = off
  double stiffness = 0.0;             // Pa, WCSPH p = k (rho/rho0 - 1); 0 = derive from max speed
  double max_speed = 0.0;  // m/s, expected speed for deriving stiffness (0 = from heights)
  KernelKind kernel = KernelKind::CubicSpline;
  std::vector<FluidBlockSpec> blocks;
  std::vector<EmitterSpec> emitters;
  int max_particles = 0;  // capacity for emitters; 0 = estimate from emitters
};

struct DomainSpec {
  Vec3d lo{0.0, 0.0, 0.0};  // m, inner corner of the tank
  Vec3d hi{1.0, 1.0, 1.0};  // m
  bool open_top = false;    // no lid: particles above hi.y are still clamped to the domain
};

struct OutputSpec {
  double fps = 30.0;            // frames per simulated second
  bool vtu = true;              // VTK XML unstructured grid frames (ParaView)
  bool ply = false;             // binary PLY point frames (Houdini, MeshLab)
  Vec3d camera_position;        // m, where pictures look from; equal to camera_target = automatic
  Vec3d camera_target;          // m
  double camera_fov = 40;       // degrees, vertical
  double checkpoint_every = 0;  // s of simulated time; 0 = a checkpoint at the end only
};

enum class GaugeKind { Pressure, Height, Node };

struct GaugeSpec {
  std::string name;
  GaugeKind kind = GaugeKind::Pressure;
  Vec3d position;    // m; for Height only x and z are used; Node: nearest rest node
  std::string body;  // Node: the body whose node is followed
};

enum class BodyShape { Box, Tube, Cup, Sphere, Cloth, Mesh };

struct PinBoxSpec {
  Vec3d lo, hi;  // m, nodes whose rest position lies in this box are held fixed
};

struct PinSpec {
  std::vector<PinBoxSpec> boxes;
  std::vector<int> nodes;  // node indices of the body's mesh, from 0
};

// One deformable body: a generated shape or a mesh file, its material and fixings.
struct BodySpec {
  std::string name;
  BodyShape shape = BodyShape::Box;
  Vec3d position;              // m: centre (box, sphere, cloth) or centre of the base (tube, cup)
  Vec3d size{0.1, 0.1, 0.1};   // m: box edges; cloth extents along x and z
  double radius = 0.05;        // m: sphere; outer radius of tube and cup
  double inner_radius = 0.04;  // m: tube and cup
  double length = 0.2;         // m: tube, along +y
  double height = 0.1;         // m: cup, along +y
  double thickness = 0.01;     // m: cloth (along y); cup bottom
  int resolution = 8;          // cells across the largest extent
  std::string file;            // mesh: relative to the scene file's folder
  double scale = 1.0;          // mesh: x -> scale x + offset
  Vec3d offset;                // m, mesh
  double max_volume = TetgenOptions{}.max_volume;  // m^3, surface meshes: TetGen "a"
  double quality = TetgenOptions{}.quality;        // surface meshes: TetGen "q"
  double peel_caps = TetgenOptions{}.peel_caps;    // surface meshes: peel_flat_caps
  Material material;
  Vec3d velocity;  // m/s, initial velocity of the free nodes
  PinSpec pinned;
  double restitution = 0.0;  // fluid contact: share of the normal relative velocity reversed
  double slip = 1.0;         // fluid contact: share of the tangential relative velocity kept
};

enum class ObstacleShape { Box, Mesh };

// One pose on an obstacle's path: at `time` the obstacle, as placed, is turned by `angle`
// about `axis` through its `pivot` and then moved by `translate`.
struct ObstacleKeySpec {
  double time = 0;      // s
  Vec3d translate;      // m
  Vec3d axis{0, 1, 0};  // direction only
  double angle = 0;     // degrees, right-handed about axis
};

// An obstacle: a box or a triangle surface (open ones too: a funnel, a slide, a plate) that the
// fluid and the bodies meet, without an FEM solve; it stays put or moves along a given path.
struct ObstacleSpec {
  std::string name;
  ObstacleShape shape = ObstacleShape::Box;
  Vec3d lo{0, 0, 0}, hi{0.1, 0.1, 0.1};  // m, box corners
  std::string file;                      // mesh: relative to the scene file's folder
  double scale = 1.0;                    // mesh: x -> scale x + offset
  Vec3d offset;                          // m, mesh
  double restitution = 0.0;              // fluid contact, as a body's
  double slip = 1.0;
  // A prescribed rigid motion: poses by time, interpolated between keys and held before the
  // first and after the last. Empty: the obstacle stays where it is placed.
  std::vector<ObstacleKeySpec> path;
  Vec3d pivot;  // m, the point the path's rotations turn about
};

enum class FemPreconditioner { BlockJacobi, TwoLevel };

// Settings of the FEM solve shared by all bodies; defaults are the solver's own.
struct FemSpec {
  double cg_tolerance = FemSettings{}.cg_tolerance;
  int cg_max_iterations = FemSettings{}.cg_max_iterations;
  FemPreconditioner preconditioner = FemPreconditioner::BlockJacobi;
  int newton_iterations = FemSettings{}.newton_iterations;
  int rotation_iterations = FemSettings{}.rotation_iterations;
  double friction = FemSettings{}.friction;  // Coulomb, nodes on walls, obstacles, surfaces
  bool contact = false;                      // surfaces meet each other and themselves
  double contact_gap = 0;                    // m, kept between touching surfaces; 0: auto
  int contact_halvings = 4;  // a body step met too deep is taken again in halves, this deep
};

enum class CouplingMethod { RayTraced, BoundaryParticles };

// How the fluid and the bodies exchange momentum (paper §3.3-4 and its baseline).
struct CouplingSpec {
  CouplingMethod method = CouplingMethod::RayTraced;
  double skin = 0.25;                // fraction of the particle radius kept off a surface
  bool near_surface_density = true;  // add the kernel mass missing beyond a body's surface
  bool implicit_exchange = false;    // the joint exchange sees the bodies' implicit response
  bool tank_rays = true;             // the tank's faces join the ray cast as static colliders
  double rebuild_quality = 2.0;      // rebuild a BVH when its box area grows by this factor
  double wall_restitution = 0.0;     // the tank's faces (static colliders)
  double wall_slip = 1.0;
};

struct SceneSpec {
  std::string path;  // file it was loaded from ("" when built in code)
  std::string name;
  SimulationSpec simulation;
  FluidSpec fluid;
  DomainSpec domain;
  OutputSpec output;
  std::vector<GaugeSpec> gauges;
  std::vector<BodySpec> bodies;
  std::vector<ObstacleSpec> obstacles;
  FemSpec fem;
  CouplingSpec coupling;

  bool has_fluid() const { return !fluid.blocks.empty() || !fluid.emitters.empty(); }
};

}  // namespace sphfem
