// Scene -> FluidModel: particle mass from the kernel, lattice blocks, tank wall samples,
// emitter discs, the grid and the capacity; the WCSPH stiffness and time-step limit a scene
// implies.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "sphfem/scene/compile.h"
#include "sphfem/scene/limits.h"

namespace sphfem {

namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 to_real(const Vec3d& v) { return Vec3(v); }

// Lattice coordinates along one axis: `inner` points inside [lo, hi] at lo + (i + 1/2) d,
// and `layers` points beyond each face at the same spacing.
std::vector<double> axis_points(double lo, double hi, double d, int layers, bool low_wall,
                                bool high_wall) {
  std::vector<double> pts;
  if (low_wall)
    for (int k = layers - 1; k >= 0; --k) pts.push_back(lo - (k + 0.5) * d);
  const int inner = std::max(1, int(std::floor((hi - lo) / d + 1e-6)));
  for (int i = 0; i < inner; ++i) pts.push_back(lo + (i + 0.5) * d);
  if (high_wall)
    for (int k = 0; k < layers; ++k) pts.push_back(hi + (k + 0.5) * d);
  return pts;
}

int emitted_layers(const EmitterModel& e, double duration) {
  const double active = std::max(0.0, std::min<double>(e.end, duration) - e.start);
  return int(std::ceil(e.speed * active / e.layer_spacing)) + 1;
}

}  // namespace

double wcsph_stiffness(const SceneSpec& s) {
  if (s.fluid.stiffness > 0) return s.fluid.stiffness;
  // Weakly compressible: c = 10 v keeps density errors near 1 % (Monaghan 1994).
  const double g = norm(s.simulation.gravity);
  double v = s.fluid.max_speed;
  const double height = s.domain.hi.y - s.domain.lo.y;
  v = std::max(v, std::sqrt(2.0 * g * height));
  for (const EmitterSpec& e : s.fluid.emitters)
    v = std::max(v, e.speed + std::sqrt(2.0 * g * height));
  const double c = 10.0 * std::max(v, 0.1);
  return s.fluid.rest_density * c * c;
}

double wcsph_dt_limit(const SceneSpec& s, double v) {
  const double c = std::sqrt(wcsph_stiffness(s) / s.fluid.rest_density);
  return s.simulation.cfl * 2.0 * s.fluid.particle_radius / (c + v);
}

std::string check_solver_settings(const SceneSpec& s) {
  if (s.simulation.solver != SolverKind::WCSPH) return "";
  const double limit = wcsph_dt_limit(s, 0.0);
  if (s.simulation.dt_min > limit) {
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "simulation.dt_min: %.4g s is above the CFL limit %.4g s of WCSPH (sound speed "
                  "%.3g m/s from fluid.stiffness %.4g Pa); lower simulation.dt_min below %.4g, "
                  "lower fluid.stiffness, raise simulation.cfl, or use solver \"dfsph\"",
                  s.simulation.dt_min, limit, std::sqrt(wcsph_stiffness(s) / s.fluid.rest_density),
                  wcsph_stiffness(s), limit);
    return buf;
  }
  return "";
}

FluidModel compile_fluid(const SceneSpec& s) {
  // Counted before the lattices are filled, for scenes built in code (a loaded scene was
  // checked with its memory by validate_scene): ints below would overflow past these caps.
  const SceneSize size = scene_size(s);
  if (size.grid_cells > kMaxGridCells || size.wall_samples > kMaxWallSamples)
    throw std::runtime_error("domain: the cell grid would have " + std::to_string(size.grid_cells) +
                             " cells and the walls " + std::to_string(size.wall_samples) +
                             " samples; make the domain smaller or the particles larger");
  if (size.capacity > kMaxParticles)
    throw std::runtime_error("fluid: the scene would need about " + std::to_string(size.capacity) +
                             " particles; use larger particles or fewer emitters");
  FluidModel m;
  SphParams& P = m.params;
  const FluidSpec& fl = s.fluid;
  const Real d = Real(2.0 * fl.particle_radius);
  P.spacing = d;
  P.h = Real(2) * d;  // support radius: about 33 neighbours on the lattice
  P.h2 = P.h * P.h;
  P.kernel = Kernel(fl.kernel == KernelKind::CubicSpline ? 0 : 1, P.h);
  P.rho0 = Real(fl.rest_density);
  P.mass = lattice_mass(P.kernel, d, P.rho0);
  P.volume = P.mass / P.rho0;
  P.stiffness = Real(wcsph_stiffness(s));
  P.sound_speed = Real(std::sqrt(double(P.stiffness) / fl.rest_density));
  P.viscosity = Real(fl.viscosity);
  P.xsph = Real(fl.xsph);
  P.alpha_av = Real(fl.artificial_viscosity);
  P.gravity = to_real(s.simulation.gravity);
  P.clamp_lo = to_real(s.domain.lo);
  P.clamp_hi = to_real(s.domain.hi);
  {
    int count = 0;
    const int r = 3;
    for (int i = -r; i <= r; ++i)
      for (int j = -r; j <= r; ++j)
        for (int k = -r; k <= r; ++k)
          if (double(i * i + j * j + k * k) * d * d < double(P.h2)) ++count;
    P.full_neighbors = count;
  }

  m.solver = s.simulation.solver;
  m.dt_min = s.simulation.dt_min;
  m.dt_max = s.simulation.dt_max;
  m.cfl = s.simulation.cfl;
  m.density_tolerance = s.simulation.density_tolerance;
  m.divergence_tolerance = s.simulation.divergence_tolerance;
  m.max_iterations = s.simulation.max_iterations;

  // Blocks on the lattice lo + (i + 1/2) d, matching the wall samples.
  for (const FluidBlockSpec& b : fl.blocks) {
    const Vec3d ext = b.hi - b.lo;
    const int nx = std::max(1, int(std::floor(ext.x / d + 1e-6)));
    const int ny = std::max(1, int(std::floor(ext.y / d + 1e-6)));
    const int nz = std::max(1, int(std::floor(ext.z / d + 1e-6)));
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          m.x0.push_back(Vec3(Real(b.lo.x + (i + 0.5) * d), Real(b.lo.y + (j + 0.5) * d),
                              Real(b.lo.z + (k + 0.5) * d)));
          m.v0.push_back(to_real(b.velocity));
        }
  }

  // Tank walls: layers of frozen lattice beyond every face, deep enough to fill the kernel
  // support of a particle touching the wall. On this regular lattice Akinci's
  // psi = rho0 / sum_k W_bk of a full neighbourhood equals the fluid particle mass.
  const int layers = int(std::ceil(double(P.h) / d));
  const std::vector<double> ax = axis_points(s.domain.lo.x, s.domain.hi.x, d, layers, true, true);
  const std::vector<double> ay =
      axis_points(s.domain.lo.y, s.domain.hi.y, d, layers, true, !s.domain.open_top);
  const std::vector<double> az = axis_points(s.domain.lo.z, s.domain.hi.z, d, layers, true, true);
  for (double z : az)
    for (double y : ay)
      for (double x : ax) {
        const bool inside = x > s.domain.lo.x && x < s.domain.hi.x && y > s.domain.lo.y &&
                            y < s.domain.hi.y && z > s.domain.lo.z && z < s.domain.hi.z;
        if (inside) continue;
        m.boundary_x.push_back(Vec3(Real(x), Real(y), Real(z)));
        m.boundary_psi.push_back(P.mass);
      }

  // Grid of cell size h over the domain and its walls.
  const double pad = layers * d + P.h;
  m.grid.cell = P.h;
  m.grid.lo = Vec3(Real(s.domain.lo.x - pad), Real(s.domain.lo.y - pad), Real(s.domain.lo.z - pad));
  m.grid.nx = int(std::ceil((s.domain.hi.x - s.domain.lo.x + 2 * pad) / P.h));
  m.grid.ny = int(std::ceil((s.domain.hi.y - s.domain.lo.y + 2 * pad) / P.h));
  m.grid.nz = int(std::ceil((s.domain.hi.z - s.domain.lo.z + 2 * pad) / P.h));

  // Emitter discs: a square lattice in the nozzle plane; the layer spacing is set so the
  // emitted volume equals pi r^2 * speed * time exactly, one layer at a time.
  for (const EmitterSpec& es : fl.emitters) {
    EmitterModel e;
    const Vec3d dir = es.direction / norm(es.direction);
    e.direction = to_real(dir);
    e.position = to_real(es.position);
    e.speed = Real(es.speed);
    e.start = Real(es.start);
    e.end = Real(std::min(es.end, 1e30));
    const Vec3d helper = std::fabs(dir.x) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
    const Vec3d u = cross(dir, helper) / norm(cross(dir, helper));
    const Vec3d w = cross(dir, u);
    const int r = int(std::ceil(es.radius / d));
    for (int i = -r; i <= r; ++i)
      for (int j = -r; j <= r; ++j) {
        const double a = i * d, b = j * d;
        if (a * a + b * b <= es.radius * es.radius + 1e-12)
          e.disc.push_back(to_real(u * a + w * b));
      }
    const double area = kPi * es.radius * es.radius;
    e.layer_spacing = Real(double(e.disc.size()) * double(P.volume) / area);
    m.emitters.push_back(e);
  }

  long long cap = (long long)m.x0.size();
  for (const EmitterModel& e : m.emitters)
    cap += (long long)e.disc.size() * emitted_layers(e, s.simulation.duration);
  if (fl.max_particles > 0) cap = std::max<long long>((long long)m.x0.size(), fl.max_particles);
  if (cap > (1ll << 30))
    throw std::runtime_error("fluid: the scene would need " + std::to_string(cap) +
                             " particles; use larger particles or fewer emitters");
  m.capacity = int(cap);
  // The model lives as long as the run (twice: the solver keeps a copy); no growth slack.
  for (std::vector<Vec3>* v : {&m.x0, &m.v0, &m.boundary_x}) v->shrink_to_fit();
  m.boundary_psi.shrink_to_fit();
  return m;
}

}  // namespace sphfem
