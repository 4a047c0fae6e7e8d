// `sphfem bench --fem`: FEM time per step for bodies at the tetrahedron counts of the paper's
// Table 1 (generated spheres, and the Stanford bunny tetrahedralised by TetGen), printed
// beside the paper's GPU times.
#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "bench.h"
#include "sphfem/fem/import.h"
#include "sphfem/fem/solver.h"
#include "sphfem/fem/tetrahedralize.h"
#include "sphfem/io/atomic_file.h"
#include "sphfem/sim/simulation.h"

namespace {

using namespace sphfem;

// Table 1 of the reference paper: FEM milliseconds per step on its GPU, by body size.
struct PaperRow {
  double tets;
  double ms;
};
constexpr PaperRow kPaper[] = {
    {1.9e3, 11.5}, {2.1e3, 11.9}, {6.4e3, 12.0}, {22.0e3, 25.6}, {34.2e3, 36.4}};

const PaperRow& nearest_paper_row(long tets) {
  const PaperRow* best = &kPaper[0];
  for (const PaperRow& r : kPaper)
    if (std::fabs(std::log(r.tets / tets)) < std::fabs(std::log(best->tets / tets))) best = &r;
  return *best;
}

constexpr double kDt = 1e-3;                 // s, a typical fluid step, which the bodies share
constexpr int kWarmUp = 10;                  // steps before measuring: caches, CG warm starts
constexpr double kBodySize = 0.2;            // m, diameter of the spheres and height of the bunny
const int kSphereCells[] = {7, 10, 15, 18};  // 2058, 6000, 20250, 34992 tetrahedra
const long kBunnyTargets[] = {6000, 22000, 34000};  // tetrahedra

struct Case {
  std::string body;
  TetMesh mesh;
  std::string how;  // how the mesh was made
};

struct Result {
  std::string body, how;
  long tets = 0, nodes = 0;
  double ms = 0, cg = 0;
  double bytes_per_tet = 0;  // heap the solver and its model hold, nodes included
  BodyProfile prof;
};

// The bunny at about `target` tetrahedra. TetGen has no count option: the coarsest mesh
// (no quality refinement, no volume bound) is tried first, then quality 2, then a bisection
// of the volume bound on a log scale until the count is within 5 %.
TetMesh mesh_near(const SurfaceMesh& s, long target, std::string& switches,
                  TetgenOptions* chosen = nullptr) {
  auto off = [&](const TetMesh& m) {
    return std::fabs(double(m.tets.size()) - double(target)) / double(target);
  };
  TetgenOptions best_o;
  best_o.quality = 0;
  TetMesh best = tetrahedralize(s, best_o);
  auto consider = [&](const TetgenOptions& o, TetMesh m) {
    if (off(m) < off(best)) best = std::move(m), best_o = o;
  };
  if (off(best) > 0.1 && long(best.tets.size()) < target) {
    TetgenOptions o;
    o.quality = 2.0;
    TetMesh m = tetrahedralize(s, o);
    const bool too_few = long(m.tets.size()) < target;
    consider(o, std::move(m));
    if (off(best) > 0.05) {
      o.quality = too_few ? 2.0 : 0.0;
      const double volume = enclosed_volume(s.x, s.tris);
      double fine = 0.1 * volume / double(target), coarse = 10.0 * volume / double(target);
      for (int it = 0; it < 12 && off(best) > 0.05; ++it) {
        o.max_volume = std::sqrt(fine * coarse);
        m = tetrahedralize(s, o);
        (long(m.tets.size()) > target ? fine : coarse) = o.max_volume;
        consider(o, std::move(m));
      }
    }
  }
  switches = tetgen_switches(best_o);
  if (chosen) *chosen = best_o;
  return best;
}

Result run_case(const Case& c, Backend backend, int steps, double young, bool two_level) {
  Material mat;  // rubber: density 1000 kg/m^3, E 100 kPa (soft) unless --young, nu 0.3
  mat.density = 1000.0, mat.young = young, mat.poisson = 0.3;
  // The bottom 5 % pinned: gravity keeps the body deforming, so CG has real work each step.
  const auto [lo, hi] = bounds(c.mesh.x);
  const double cut = lo.y + 0.05 * (hi.y - lo.y);
  const auto pinned = pin_nodes(c.mesh, [&](const Vec3d& x) { return x.y <= cut; });
  FemSettings set;  // the solver's defaults, as a scene without a `fem` section gets
  set.two_level = two_level;
  malloc_trim(0);
  const double heap0 = heap_held_bytes();
  auto solver = make_body_solver(std::make_shared<const BodiesModel>(compile_bodies(
                                     {compile_body(c.mesh, mat, pinned, c.body)}, set)),
                                 backend);
  for (int i = 0; i < kWarmUp; ++i) solver->step(kDt);
  const double held = heap_held_bytes() - heap0;
  solver->reset_profile();
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < steps; ++i) solver->step(kDt);
  Result r;
  r.body = c.body;
  r.how = c.how;
  r.tets = long(c.mesh.tets.size());
  r.nodes = long(c.mesh.x.size());
  r.bytes_per_tet = held / double(std::max(1L, r.tets));
  r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
         steps;
  r.prof = solver->profile();
  r.cg = double(r.prof.cg_iterations) / double(std::max(1L, r.prof.steps));
  return r;
}

// The bunny standing free on the tank's floor, through a whole Simulation (bodies only): its
// walls held inside the solve, and with fem.contact its surface tested against itself. Times
// per step of the stages fem and body_contact, after it has settled.
struct Resting {
  long tets = 0;
  double ms_fem = 0, ms_contact = 0, held = 0, pairs = 0;
};

Resting run_resting(const std::string& file, double scale, const Vec3d& offset,
                    const TetgenOptions& o, bool contact, int steps) {
  SceneSpec s;
  s.path = "bench";
  s.domain.lo = Vec3d(-0.2, 0, -0.2);
  s.domain.hi = Vec3d(0.2, 0.3, 0.2);
  BodySpec b;
  b.name = "bunny";
  b.shape = BodyShape::Mesh;
  b.file = std::filesystem::absolute(file).string();
  b.scale = scale;
  b.offset = offset;
  b.quality = o.quality;
  b.max_volume = o.max_volume;
  b.material.density = 1000.0, b.material.young = 1e5, b.material.poisson = 0.3;
  b.material.beta = 0.002;
  s.bodies.push_back(b);
  s.fem.contact = contact;
  Simulation sim(s, Backend::Cpu);
  for (int i = 0; i < 100; ++i) sim.step(kDt);  // lands (it starts a millimetre up) and settles
  sim.reset_profile();
  (void)sim.take_body_contact_tally();
  for (int i = 0; i < steps; ++i) sim.step(kDt);
  const StepProfile& p = sim.profile();
  const BodyContactTally t = sim.take_body_contact_tally();
  Resting r;
  r.tets = long(sim.bodies_model().tets.size());
  r.ms_fem = p.ms[int(Stage::Fem)] / steps;
  r.ms_contact = p.ms[int(Stage::BodyContact)] / steps;
  r.held = double(t.held) / double(std::max(1L, t.steps));
  r.pairs = double(t.pairs) / double(std::max(1L, t.steps));
  return r;
}

// The surface to tetrahedralise, scaled to kBodySize tall and standing on y = 0; an empty
// surface when the default bunny has not been fetched.
SurfaceMesh bunny_surface(const BenchOptions& opt) {
  const std::string path = opt.mesh.empty() ? "build/assets/bunny.obj" : opt.mesh;
  if (opt.mesh.empty() && !std::filesystem::exists(path)) {
    std::printf(
        "bunny: %s not found, so only spheres are measured; fetch it with "
        "scripts/fetch-bunny.sh build/assets, or pass --mesh PATH\n",
        path.c_str());
    return {};
  }
  SurfaceMesh s = load_surface(path);
  const auto [lo, hi] = bounds(s.x);
  const double scale = kBodySize / (hi.y - lo.y);
  const Vec3d centre = (lo + hi) * 0.5;
  transform(s, scale, Vec3d(-centre.x * scale, -lo.y * scale, -centre.z * scale));
  return s;
}

std::string thousands(long n) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1fk", n / 1000.0);
  return buf;
}

}  // namespace

int run_fem_bench(const BenchOptions& opt) {
  if (opt.threads > 0) set_cpu_threads(opt.threads);
  const Backend backend = opt.backend == "cuda" ? Backend::Cuda : Backend::Cpu;
  const std::string device = backend == Backend::Cpu ? cpu_model() : cuda_device_name();

  std::vector<Case> cases;
  for (int cells : kSphereCells)
    if (!opt.resting)
      cases.push_back({"sphere", make_sphere(Vec3d(0, 0, 0), 0.5 * kBodySize, cells),
                       "make_sphere, " + std::to_string(cells) + " cells across"});
  const SurfaceMesh bunny = bunny_surface(opt);
  if (!bunny.tris.empty() && !opt.resting) {
    const std::string name = std::filesystem::path(opt.mesh.empty() ? "bunny" : opt.mesh).stem();
    for (long target : kBunnyTargets) {
      std::string switches;
      TetMesh m = mesh_near(bunny, target, switches);
      cases.push_back({name, std::move(m), "TetGen -" + switches});
    }
  }
  std::sort(cases.begin(), cases.end(),
            [](const Case& a, const Case& b) { return a.mesh.tets.size() < b.mesh.tets.size(); });

  std::printf(
      "FEM benchmark on %s, %d threads, %s backend: implicit Euler, dt %g ms, E %g kPa, "
      "bottom 5 %% pinned, %d steps after %d warm-up\n\n",
      device.c_str(), cpu_threads(), opt.backend.c_str(), kDt * 1e3, opt.young / 1e3, opt.steps,
      kWarmUp);
  std::printf("%-8s %7s %7s %9s %8s %7s   %-22s %s\n", "body", "tets", "nodes", "ms/step", "CG it",
              "B/tet", "paper GPU (Table 1)", "mesh");
  char line[1024];
  std::string csv;
  // Rows of other than the default soft body and block Jacobi go to their own file.
  const bool options = opt.young != 1e5 || opt.two_level;
  std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
  for (const Case& c : cases) {
    const Result r = run_case(c, backend, opt.steps, opt.young, opt.two_level);
    const PaperRow& p = nearest_paper_row(r.tets);
    char paper[64];
    std::snprintf(paper, sizeof paper, "%s tets %5.1f ms", thousands(long(p.tets)).c_str(), p.ms);
    std::printf("%-8s %7ld %7ld %9.2f %8.1f %7.0f   %-22s %s\n", r.body.c_str(), r.tets, r.nodes,
                r.ms, r.cg, r.bytes_per_tet, paper, r.how.c_str());
    std::fflush(stdout);
    const double per = 1.0 / double(std::max(1L, r.prof.steps));
    std::snprintf(line, sizeof line,
                  "%s,\"%s\",%d,%s,%s,%ld,%ld,%d,%g,%.3f,%.3f,%.3f,%.3f,%.3f,%.1f,%.0f,%.1f", date,
                  device.c_str(), cpu_threads(), opt.backend.c_str(), r.body.c_str(), r.tets,
                  r.nodes, opt.steps, kDt, r.prof.ms_rotations * per, r.prof.ms_assemble * per,
                  r.prof.ms_solve * per, r.prof.ms_integrate * per, r.ms, r.cg, p.tets, p.ms);
    csv += line;
    if (options) {
      std::snprintf(line, sizeof line, ",%g,%s", opt.young,
                    opt.two_level ? "two_level" : "block_jacobi");
      csv += line;
    }
    csv += "\n";
  }
  if (!cases.empty()) std::printf("peak RSS %.1f MB\n", peak_rss_bytes() / 1e6);
  if (!opt.out_dir.empty() && !cases.empty()) {
    std::printf("\n");
    const std::string header =
        "date,device,threads,backend,body,tets,nodes,steps,dt,ms_rotations,ms_assemble,"
        "ms_solve,ms_integrate,ms_step,cg_iterations,paper_tets,paper_gpu_ms";
    append_results(opt.out_dir, options ? "fem_options.csv" : "fem.csv",
                   options ? header + ",young,preconditioner" : header, csv);
  }
  if (!bunny.tris.empty() && backend == Backend::Cpu) {
    // The same bunny at about 22k tetrahedra standing free on the floor, contact on and off.
    const std::string file = opt.mesh.empty() ? "build/assets/bunny.obj" : opt.mesh;
    const SurfaceMesh raw = load_surface(file);
    const auto [lo, hi] = bounds(raw.x);
    const double scale = kBodySize / (hi.y - lo.y);
    const Vec3d centre = (lo + hi) * 0.5;
    const Vec3d offset(-centre.x * scale, 0.001 - lo.y * scale, -centre.z * scale);
    std::string switches;
    TetgenOptions o;
    mesh_near(bunny, kBunnyTargets[1], switches, &o);
    std::printf("\nresting on the floor (walls inside the solve), %d steps after 100:\n",
                opt.steps);
    std::printf("%-22s %7s %9s %13s %10s %8s\n", "", "tets", "ms fem", "ms contact", "held",
                "pairs");
    std::string rows;
    for (bool contact : {false, true}) {
      const Resting r = run_resting(file, scale, offset, o, contact, opt.steps);
      std::printf("%-22s %7ld %9.2f %8.2f (%2.0f%%) %10.1f %8.1f\n",
                  contact ? "fem.contact on" : "fem.contact off", r.tets, r.ms_fem, r.ms_contact,
                  100.0 * r.ms_contact / r.ms_fem, r.held, r.pairs);
      std::snprintf(line, sizeof line, "%s,\"%s\",%d,bunny_resting,%ld,%d,%d,%.3f,%.3f,%.1f,%.1f\n",
                    date, device.c_str(), cpu_threads(), r.tets, int(contact), opt.steps, r.ms_fem,
                    r.ms_contact, r.held, r.pairs);
      rows += line;
    }
    if (!opt.out_dir.empty())
      append_results(opt.out_dir, "fem_contact.csv",
                     "date,device,threads,case,tets,surface_contact,steps,ms_fem,ms_body_contact,"
                     "wall_held_nodes,contact_pairs",
                     rows);
  }
  return 0;
}
