// `sphfem bench`: the dam-break workload of the SPH benchmark (a 40^3 block of particles of
// radius 0.0125 m in a 4 x 3 x 1.5 m tank, fixed 1 ms step), ms/step per phase; and with
// --fem the FEM bodies at the sizes of the paper's Table 1 (bench_fem.cpp).
#pragma once

#include <string>

struct BenchOptions {
  int steps = 200;
  int side = 0;  // 0: the workload's own (dam break 40^3; --paper 45 x 32 x 45)
  std::string solver = "both";
  int threads = 0;
  std::string backend = "cpu";
  std::string out_dir;
  bool fem = false;
  std::string mesh;        // --fem: surface to tetrahedralise; empty = the fetched bunny
  bool resting = false;    // --fem: only the bunny resting on the floor (fem_contact.csv)
  double young = 1e5;      // --fem: Young's modulus of the bodies, Pa
  bool two_level = false;  // --fem: the CG's coarse level (fem.preconditioner two_level)
  bool paper = false;
  std::string method = "all";  // --paper: raytraced, raytraced_paper, boundary_particles, both, all
  std::string scenes;          // --paper: folder of the paper's scenes (default scenes/paper)
};

// Measured steps of the FEM benchmark when --steps is not given.
constexpr int kFemBenchSteps = 50;

int run_bench(const BenchOptions& opt);
std::string cpu_model();  // the CPU's model name, for result files
// Appends rows to dir/file, writing the header line first when the file is new.
void append_results(const std::string& dir, const std::string& file, const std::string& header,
                    const std::string& rows);
int run_fem_bench(const BenchOptions& opt);
// Bytes the heap holds now (glibc's mallinfo2, mapped chunks included): what a solver holds is
// the difference around its construction and first steps.
double heap_held_bytes();
// The process's peak resident set so far, in bytes.
double peak_rss_bytes();
int run_paper_bench(const BenchOptions& opt);  // Table 1 of the paper (bench_paper.cpp)
// Measured steps of the paper benchmark when --steps is not given.
constexpr int kPaperBenchSteps = 50;
