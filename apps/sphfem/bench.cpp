#include "bench.h"

#include <malloc.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>

#include "bench_machine.h"
#include "sphfem/io/atomic_file.h"
#include "sphfem/scene/compile.h"
#include "sphfem/sph/solver.h"

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown CPU";
}

double heap_held_bytes() {
  const struct mallinfo2 m = mallinfo2();
  return double(m.uordblks + m.hblkhd);
}

double peak_rss_bytes() {
  struct rusage u {};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) * 1024.0;  // kilobytes on Linux
}

namespace {

using namespace sphfem;

SceneSpec bench_scene(SolverKind solver, int side) {
  SceneSpec s;
  s.name = "benchmark dam break";
  s.simulation.solver = solver;
  s.simulation.dt_min = s.simulation.dt_max = 1e-3;
  s.simulation.cfl = 1.0;
  s.fluid.particle_radius = 0.0125;
  s.fluid.viscosity = 1e-6;
  // Sound speed 15 m/s keeps the fixed 1 ms step inside the acoustic CFL limit.
  s.fluid.stiffness = 1000.0 * 15.0 * 15.0;
  s.domain.lo = Vec3d(0, 0, 0);
  s.domain.hi = Vec3d(4, 3, 1.5);
  const double e = side * 0.025;
  s.fluid.blocks.push_back({Vec3d(0, 0, 0), Vec3d(e, e, e), Vec3d()});
  return s;
}

}  // namespace

int run_bench(const BenchOptions& opt) {
  if (opt.threads > 0) set_cpu_threads(opt.threads);
  const Backend backend = opt.backend == "cuda" ? Backend::Cuda : Backend::Cpu;
  std::string csv;
  char line[1024];
  std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
  const std::string device = backend == Backend::Cpu ? cpu_model() : cuda_device_name();
  std::printf("dam-break benchmark on %s, %d threads, %s backend\n", device.c_str(), cpu_threads(),
              opt.backend.c_str());
  for (SolverKind kind : {SolverKind::WCSPH, SolverKind::DFSPH}) {
    const char* name = kind == SolverKind::WCSPH ? "wcsph" : "dfsph";
    if (opt.solver != "both" && opt.solver != name) continue;
    malloc_trim(0);
    const double heap0 = heap_held_bytes();
    const FluidModel model = compile_fluid(bench_scene(kind, opt.side > 0 ? opt.side : 40));
    auto solver = make_fluid_solver(model, backend);
    for (int i = 0; i < 20; ++i) solver->step(1.0);  // warm-up: caches, allocations
    const double held = heap_held_bytes() - heap0;
    solver->reset_profile();
    long iters = 0, div_iters = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < opt.steps; ++i) {
      const StepInfo info = solver->step(1.0);
      iters += info.pressure_iterations;
      div_iters += info.divergence_iterations;
    }
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
        opt.steps;
    const StepProfile& p = solver->profile();
    std::printf("\n%s: %d particles, %zu wall samples, dt 1 ms, %d steps after 20 warm-up\n", name,
                solver->count(), model.boundary_x.size(), opt.steps);
    std::string phases;
    for (int k = 0; k < int(Stage::Count); ++k) {
      const double v = p.ms[k] / p.steps;
      if (v > 0) std::printf("  %-12s %8.2f ms/step\n", stage_name(Stage(k)), v);
      std::snprintf(line, sizeof line, ",%.3f", v);
      phases += line;
    }
    const double mps = solver->count() / (ms * 1e-3) / 1e6;
    std::printf("  %-12s %8.2f ms/step  (%.2f M particle-steps/s", "total", ms, mps);
    if (kind == SolverKind::DFSPH)
      std::printf(", %.1f pressure and %.1f divergence iterations/step", double(iters) / opt.steps,
                  double(div_iters) / opt.steps);
    std::printf(")\n");
    std::printf("  %-12s %8.1f MB held (%.0f B a particle, walls included), peak RSS %.1f MB\n",
                "memory", held / 1e6, held / solver->count(), peak_rss_bytes() / 1e6);
    std::snprintf(line, sizeof line, "%s,\"%s\",%d,%s,%s,%d,%d%s,%.3f,%.3f,%.2f\n", date,
                  device.c_str(), cpu_threads(), opt.backend.c_str(), name, solver->count(),
                  opt.steps, phases.c_str(), ms, mps, double(iters) / opt.steps);
    csv += line;
  }
  if (backend == Backend::Cpu) {
    // After the runs, whose peak memory is already printed: the machine's speed at the time,
    // against which results of other times are read (bench/results/README.md).
    const MachineNow m = measure_machine(cpu_threads());
    std::printf(
        "\nmachine now: stream triad %.1f GB/s (%d threads), dependent multiply-add %.3f ns\n",
        m.triad_gbs, m.threads, m.fma_chain_ns);
  }
  if (!opt.out_dir.empty()) {
    io::ensure_directory(opt.out_dir);
    const std::string path = opt.out_dir + "/sph_dam_break.csv";
    std::string header = "date,device,threads,backend,solver,particles,steps";
    for (int k = 0; k < int(Stage::Count); ++k)
      header += ",ms_" + std::string(stage_name(Stage(k)));
    header += ",ms_step,mparticle_steps_per_s,pressure_iterations";
    std::string first;
    if (std::ifstream old(path); old) std::getline(old, first);
    // Rows of another column set (an older stage list) are kept in a file of their own.
    if (!first.empty() && first != header)
      std::filesystem::rename(path, opt.out_dir + "/sph_dam_break_" + date + "_before.csv");
    std::printf("\n");
    append_results(opt.out_dir, "sph_dam_break.csv", header, csv);
  }
  return 0;
}

void append_results(const std::string& dir, const std::string& file, const std::string& header,
                    const std::string& rows) {
  io::ensure_directory(dir);
  const std::string path = dir + "/" + file;
  const bool fresh = !std::filesystem::exists(path);
  std::ofstream f(path, std::ios::app);
  if (fresh) f << header << "\n";
  f << rows;
  std::printf("results appended to %s\n", path.c_str());
}
