// How fast the machine is at the moment of a benchmark. A virtual machine's cores run faster or
// slower from minute to minute (1.5x between phases has been seen, bench/results/README.md),
// so `sphfem bench` measures the machine beside its runs and prints it with the result.
#pragma once

struct MachineNow {
  int threads = 0;
  double triad_gbs = 0;     // stream triad c = a + s b, 32 MiB arrays, these threads, best of 5
  double fma_chain_ns = 0;  // one thread's dependent float multiply-add, ns a link, best of 3
};

// Takes about half a second and 96 MiB, freed on return: call it after the peak memory has
// been read.
MachineNow measure_machine(int threads);
