// CUDA backend of the execution layer: the same calls as exec_cpu.h, run as kernels on one
// stream; CUB does the sort, scan and reductions. Only .cu files include this header.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>
#include <vector>

#include "sphfem/core/memory.h"

namespace sphfem {

// Throws std::runtime_error naming `what`, the stage running (set_stage_label) and, when
// given, the source line of the launch.
void cuda_check(cudaError_t e, const char* what, const char* file = nullptr, int line = 0);
// SPHFEM_CUDA_CHECK=1: synchronise after every launch (read once).
bool cuda_sync_checks();

// temp and scratch grow to twice their size when too small and keep what they outgrow until
// the destructor: cudaFree synchronises the device, so none may run inside a step (the old
// block may also still be in use by queued work). Doubling keeps the kept blocks below the
// live one in size, and a run stops growing after its first steps.
struct CudaExec {
  static constexpr MemSpace kSpace = MemSpace::Device;
  cudaStream_t stream = nullptr;
  void* tmp = nullptr;  // CUB temporary storage, grown on demand
  std::size_t tmp_bytes = 0;
  std::uint32_t* scratch = nullptr;  // sort ping-pong and reduction results
  std::size_t scratch_n = 0;
  std::vector<void*> outgrown;  // freed by the destructor
  CudaExec();
  ~CudaExec();
  CudaExec(const CudaExec&) = delete;
  CudaExec& operator=(const CudaExec&) = delete;
  void* temp(std::size_t bytes);
  std::uint32_t* scratch_u32(std::size_t n);
};

template <class F>
__global__ void parallel_for_kernel(int n, F f) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) f(i);
}

// The launch site is the caller's line (GCC's and Clang's __builtin_FILE/__builtin_LINE as
// default arguments), which names the kernel in an error.
template <class F>
void parallel_for(CudaExec& ex, int n, F f, const char* file = __builtin_FILE(),
                  int line = __builtin_LINE()) {
  if (n <= 0) return;
  constexpr int kBlock = 256;
  parallel_for_kernel<<<(n + kBlock - 1) / kBlock, kBlock, 0, ex.stream>>>(n, f);
  cuda_check(cudaGetLastError(), "kernel launch", file, line);
  if (cuda_sync_checks()) cuda_check(cudaStreamSynchronize(ex.stream), "kernel", file, line);
}

// The same: a device has no schedule to choose (exec_cpu.h's parallel_for_light).
template <class F>
void parallel_for_light(CudaExec& ex, int n, F f, const char* file = __builtin_FILE(),
                        int line = __builtin_LINE()) {
  parallel_for(ex, n, f, file, line);
}

template <class T, class F>
T reduce_max(CudaExec& ex, int n, T init, F f) {
  if (n <= 0) return init;
  T* vals = reinterpret_cast<T*>(ex.scratch_u32((n + 1) * sizeof(T) / 4 + 2));
  parallel_for(ex, n, [=] __device__(int i) { vals[i] = f(i); });
  T* out = vals + n;
  std::size_t bytes = 0;
  cuda_check(cub::DeviceReduce::Max(nullptr, bytes, vals, out, n, ex.stream), "cub max");
  cuda_check(cub::DeviceReduce::Max(ex.temp(bytes), bytes, vals, out, n, ex.stream), "cub max");
  T r;
  cuda_check(cudaMemcpyAsync(&r, out, sizeof(T), cudaMemcpyDeviceToHost, ex.stream), "reduce");
  cuda_check(cudaStreamSynchronize(ex.stream), "reduce");
  return r > init ? r : init;
}

template <class F>
double reduce_sum(CudaExec& ex, int n, F f) {
  if (n <= 0) return 0.0;
  double* vals = reinterpret_cast<double*>(ex.scratch_u32(2 * (n + 1)));
  parallel_for(ex, n, [=] __device__(int i) { vals[i] = double(f(i)); });
  double* out = vals + n;
  std::size_t bytes = 0;
  cuda_check(cub::DeviceReduce::Sum(nullptr, bytes, vals, out, n, ex.stream), "cub sum");
  cuda_check(cub::DeviceReduce::Sum(ex.temp(bytes), bytes, vals, out, n, ex.stream), "cub sum");
  double r = 0.0;
  cuda_check(cudaMemcpyAsync(&r, out, sizeof(double), cudaMemcpyDeviceToHost, ex.stream), "reduce");
  cuda_check(cudaStreamSynchronize(ex.stream), "reduce");
  return r;
}

inline void exec_sync(CudaExec& ex) { cuda_check(cudaStreamSynchronize(ex.stream), "sync"); }

// out[i] = in[0] + ... + in[i-1]; returns the total (one round trip to read it).
std::uint32_t exclusive_scan(CudaExec& ex, const std::uint32_t* in, std::uint32_t* out, int n);

// Sort of (keys, vals) by the low key_bits of keys (CUB radix sort, stable).
void sort_pairs(CudaExec& ex, std::uint32_t* keys, std::uint32_t* vals, int n, int key_bits);

}  // namespace sphfem
