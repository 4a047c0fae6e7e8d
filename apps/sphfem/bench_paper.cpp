// `sphfem bench --paper`: the paper's Table 1 workload for each of its scenes
// (scenes/paper/*.json): the scene's body with 64,800 particles falling onto it as one block,
// measured once the block has reached the body (0.02 s after the first impulse on it). Prints FEM,
// SPH and coupling ms per step beside the paper's own numbers, with the leak counts.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bench.h"
#include "sphfem/io/atomic_file.h"
#include "sphfem/scene/load.h"
#include "sphfem/sim/simulation.h"

namespace {

using namespace sphfem;
namespace fs = std::filesystem;

// Table 1 of the reference paper (NVIDIA Quadro 6000): elements, FEM, SPH, coupling ms.
struct PaperRow {
  const char* scene;
  const char* label;
  double elements, fem, sph, coupling;
};
constexpr PaperRow kPaper[] = {{"cloth", "Cloth", 1.9e3, 11.5, 17.9, 8.0},
                               {"cup", "Cup", 2.1e3, 11.9, 17.9, 8.1},
                               {"tube_hd_hk", "Tube", 6.4e3, 12.0, 17.9, 8.3},
                               {"bunny", "Bunny", 22.0e3, 25.6, 17.9, 26.6},
                               {"dragon", "Dragon", 34.2e3, 36.4, 17.9, 41.8}};

// The scene with its emitters replaced by a block of particles above the body: side x
// 32/45 side x side particles (side 0: 45, the paper's size; smaller for a quick check).
SceneSpec table1_scene(SceneSpec s, int side) {
  s.fluid.emitters.clear();
  // The paper's SPH: the state equation with pressure proportional to density (WCSPH).
  s.simulation.solver = SolverKind::WCSPH;
  s.fluid.max_speed = 3.0;
  const double d = 2 * s.fluid.particle_radius;
  // 45 x 32 x 45 = 64,800 particles: the lattice box nearest the paper's 65,535.
  const int nx = side > 0 ? side : 45, ny = std::max(1, nx * 32 / 45), nz = nx;
  const Vec3d c = 0.5 * (s.domain.lo + s.domain.hi);
  double top = s.domain.lo.y;
  for (const BodySpec& b : s.bodies) {
    double h = b.position.y + b.size.y * 0.5;
    if (b.shape == BodyShape::Tube) h = b.position.y + b.length;
    if (b.shape == BodyShape::Cup) h = b.position.y + b.height;
    if (b.shape == BodyShape::Cloth) h = b.position.y + b.thickness;
    if (b.shape == BodyShape::Mesh) h = b.offset.y + 0.25;
    top = std::max(top, h);
  }
  // Two spacings above the body, already falling at 1 m/s as poured water arrives.
  FluidBlockSpec blk;
  blk.lo = Vec3d(c.x - 0.5 * nx * d, top + 2 * d, c.z - 0.5 * nz * d);
  blk.hi = Vec3d(c.x + 0.5 * nx * d, top + 2 * d + ny * d, c.z + 0.5 * nz * d);
  blk.velocity = Vec3d(0, -1, 0);
  s.fluid.blocks = {blk};
  s.fluid.max_particles = 0;
  s.domain.hi.y = std::max(s.domain.hi.y, blk.hi.y + 2 * d);
  return s;
}

struct Measured {
  int particles = 0, elements = 0;
  double fem = 0, sph = 0, coupling = 0, total = 0, leak_check = 0;
  long crossed = 0, inside = 0;
  double contacts = 0;
};

Measured measure(const SceneSpec& scene, Backend backend, int steps) {
  Simulation sim(scene, backend);
  FluidSolver* f = sim.fluid();
  RayCoupling* hook = sim.coupling();
  // Until the fluid first pushes a body (at most 0.3 s), then 0.02 s more, so that the
  // measured steps have the block's front spread over the body.
  auto touched = [&] {
    if (!hook) return true;
    for (const Vec3d& j : hook->stats().body_impulse)
      if (j.x != 0 || j.y != 0 || j.z != 0) return true;
    return false;
  };
  while (sim.time() < 0.3 && !touched()) sim.step(scene.simulation.dt_max);
  const double landed = sim.time() + 0.02;
  while (sim.time() < landed) sim.step(scene.simulation.dt_max);
  sim.reset_profile();
  if (hook) hook->reset_stats();
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < steps; ++i) sim.step(scene.simulation.dt_max);
  Measured m;
  m.total =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
      steps;
  const StepProfile& p = sim.profile();
  auto ms = [&](Stage st) { return p.ms[int(st)] / steps; };
  m.fem = ms(Stage::Fem);
  m.coupling =
      ms(Stage::Proximity) + ms(Stage::Collide) + ms(Stage::ContactFix) + ms(Stage::Exchange);
  m.sph = ms(Stage::Neighbors) + ms(Stage::Density) + ms(Stage::Divergence) + ms(Stage::Forces) +
          ms(Stage::Pressure) + ms(Stage::Drift) + ms(Stage::Emit);
  if (hook) {
    const RayCouplingStats& s = hook->stats();
    m.leak_check = s.ms_leak_check / steps;
    m.coupling = std::max(0.0, m.coupling - m.leak_check);
    m.crossed = s.crossed;
    m.contacts = double(s.contacts) / steps;
  }
  m.total -= m.leak_check;  // a measurement, not part of the method
  m.particles = f->count();
  m.elements = sim.bodies() ? sim.bodies_model().elements : 0;
  m.inside = sim.count_inside();
  return m;
}

}  // namespace

int run_paper_bench(const BenchOptions& opt) {
  if (opt.threads > 0) set_cpu_threads(opt.threads);
  const Backend backend = opt.backend == "cuda" ? Backend::Cuda : Backend::Cpu;
  const std::string dir = opt.scenes.empty() ? "scenes/paper" : opt.scenes;
  std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
  const std::string device = backend == Backend::Cpu ? cpu_model() : cuda_device_name();
  std::printf("paper Table 1 on %s, %d threads, %s backend, %d steps after the block lands\n",
              device.c_str(), cpu_threads(), opt.backend.c_str(), opt.steps);
  std::printf("%-8s %-19s %8s %9s | %7s %7s %8s %7s | %7s %7s %8s %7s | %6s %6s\n", "scene",
              "method", "elements", "particles", "FEM", "SPH", "coupling", "total", "paper", "SPH",
              "coupling", "total", "leaks", "hits");
  std::string csv;
  char line[1024];
  // Paper Fig. 8: ms per step and leaked particles over all scenes, per coupling.
  // The ray-traced coupling with the near-surface density (the default) and without it (the
  // paper's own mode: the per-face exchange alone keeps the water out), and the baseline.
  const char* methods[3] = {"raytraced", "raytraced_paper", "boundary_particles"};
  struct Fig8 {
    double ms = 0;
    long leaks = 0;
    double contacts = 0;
    int rows = 0;
  } fig8[3];
  for (const PaperRow& row : kPaper) {
    const std::string path = dir + "/" + row.scene + ".json";
    SceneSpec base;
    try {
      base = load_scene(path);
    } catch (const std::exception& e) {
      std::printf("%-8s skipped: %s\n", row.label, e.what());
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const char* method = methods[k];
      if (opt.method != "both" && opt.method != "all" && opt.method != method) continue;
      if (opt.method == "both" && k == 1) continue;  // "both": the two couplings of Fig. 8
      SceneSpec s = table1_scene(base, opt.side);
      s.coupling.method = k < 2 ? CouplingMethod::RayTraced : CouplingMethod::BoundaryParticles;
      s.coupling.near_surface_density = k == 0;
      Measured m;
      try {
        m = measure(s, backend, opt.steps);
      } catch (const std::exception& e) {
        std::printf("%-8s %-19s failed: %s\n", row.label, method, e.what());
        continue;
      }
      const double paper_total = row.fem + row.sph + row.coupling;
      Fig8& f8 = fig8[k];
      f8.ms += m.total;
      f8.leaks += m.crossed + m.inside;
      f8.contacts += m.contacts;
      ++f8.rows;
      std::printf(
          "%-8s %-19s %8d %9d | %7.2f %7.2f %8.2f %7.2f | %7.1f %7.1f %8.1f %7.1f | %6ld %6.0f\n",
          row.label, method, m.elements, m.particles, m.fem, m.sph, m.coupling, m.total, row.fem,
          row.sph, row.coupling, paper_total, m.crossed + m.inside, m.contacts);
      std::snprintf(
          line, sizeof line,
          "%s,\"%s\",%d,%s,%s,%s,%d,%d,%d,%.3f,%.3f,%.3f,%.3f,%.3f,%ld,%ld,%.0f,%.1f,%.1f,"
          "%.1f,%.1f\n",
          date, device.c_str(), cpu_threads(), opt.backend.c_str(), row.scene, method, m.elements,
          m.particles, opt.steps, m.fem, m.sph, m.coupling, m.total, m.leak_check, m.crossed,
          m.inside, m.contacts, row.fem, row.sph, row.coupling, paper_total);
      csv += line;
    }
  }
  std::printf("\npaper Fig. 8 (mean over the scenes run; leaks: crossings + particles inside)\n");
  for (int k = 0; k < 3; ++k)
    if (fig8[k].rows)
      std::printf("%-19s %8.2f ms/step %8ld leaks %8.0f contacts/step over %d scenes\n", methods[k],
                  fig8[k].ms / fig8[k].rows, fig8[k].leaks, fig8[k].contacts / fig8[k].rows,
                  fig8[k].rows);
  if (!opt.out_dir.empty()) {
    std::printf("\n");
    append_results(opt.out_dir, "paper_table1.csv",
                   "date,device,threads,backend,scene,method,elements,particles,steps,ms_fem,"
                   "ms_sph,ms_coupling,ms_total,ms_leak_check,crossed,inside,contacts,paper_fem,"
                   "paper_sph,paper_coupling,paper_total",
                   csv);
  }
  return 0;
}
