// `sphfem bench`: the dam-break workload of the SPH benchmark (a 40^3 block of particles of
// radius 0.0125 m in a 4 x 3 x 1.5 m tank, fixed 1 ms step), ms/step per phase.
#pragma once

#include <string>

struct BenchOptions {
  int steps = 200;
  int side = 40;
  std::string solver = "both";
  int threads = 0;
  std::string backend = "cpu";
  std::string out_dir;
};

int run_bench(const BenchOptions& opt);
