#include "bench_machine.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <vector>

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// c = a + s b over arrays well beyond the last-level cache, best of a few: three floats moved
// per element (two read, one written; the write's read for ownership not counted, as STREAM).
double triad_gbs(int threads) {
  constexpr std::ptrdiff_t n = std::ptrdiff_t(1) << 23;  // 32 MiB an array
  std::vector<float> a(n), b(n), c(n);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t i = 0; i < n; ++i) a[i] = 1.0f, b[i] = 2.0f, c[i] = 0.0f;
  double best = 1e30;
  for (int rep = 0; rep < 5; ++rep) {
    const float s = 0.5f + float(rep);
    const auto t0 = std::chrono::steady_clock::now();
#pragma omp parallel for num_threads(threads) schedule(static)
    for (std::ptrdiff_t i = 0; i < n; ++i) c[i] = a[i] + s * b[i];
    best = std::min(best, seconds_since(t0));
    a[std::size_t(rep)] = c[std::size_t(n - 1 - rep)];  // keeps every pass's result in use
  }
  return 3.0 * sizeof(float) * double(n) / best / 1e9;
}

// One thread's chain of dependent multiply-adds: its time per link follows the core's clock
// and nothing else (no memory), the measure of a slowed core.
double fma_chain_ns() {
  constexpr long links = 20'000'000;
  double best = 1e30;
  float x = 1.0f;
  for (int rep = 0; rep < 3; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    for (long k = 0; k < links; ++k) {
      x = x * 0.999999f + 1e-7f;
      asm volatile("" : "+x"(x));  // one link after another, not folded or vectorised
    }
    best = std::min(best, seconds_since(t0));
  }
  volatile float keep = x;
  (void)keep;
  return best / double(links) * 1e9;
}

}  // namespace

MachineNow measure_machine(int threads) {
  MachineNow m;
  m.threads = threads > 0 ? threads : omp_get_max_threads();
  m.triad_gbs = triad_gbs(m.threads);
  m.fma_chain_ns = fma_chain_ns();
  return m;
}
