#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "exec_cuda.cuh"
#include "sphfem/core/backend.h"

namespace sphfem {

void cuda_check(cudaError_t e, const char* what, const char* file, int line) {
  if (e == cudaSuccess) return;
  std::string where = what;
  if (const char* stage = stage_label()) where += std::string(" (stage ") + stage + ")";
  if (file) where += std::string(" launched at ") + file + ":" + std::to_string(line);
  // A fault in a kernel is sticky: every later call fails alike, so say where to look.
  throw std::runtime_error("CUDA error in " + where + ": " + cudaGetErrorString(e) +
                           (cuda_sync_checks() ? ""
                                               : "; rerun with SPHFEM_CUDA_CHECK=1 to find the "
                                                 "kernel that faulted"));
}

bool cuda_sync_checks() {
  static const bool on = [] {
    const char* v = std::getenv("SPHFEM_CUDA_CHECK");
    return v && *v && std::string(v) != "0";
  }();
  return on;
}

CudaExec::CudaExec() { cuda_check(cudaStreamCreate(&stream), "stream create"); }

CudaExec::~CudaExec() {
  for (void* p : outgrown) cudaFree(p);
  if (tmp) cudaFree(tmp);
  if (scratch) cudaFree(scratch);
  if (stream) cudaStreamDestroy(stream);
}

void* CudaExec::temp(std::size_t bytes) {
  if (bytes > tmp_bytes) {
    const std::size_t grown = std::max(bytes, 2 * tmp_bytes);
    void* p = nullptr;
    cuda_check(cudaMalloc(&p, grown), "temp alloc");
    if (tmp) outgrown.push_back(tmp);  // no cudaFree inside a step (exec_cuda.cuh)
    tmp = p;
    tmp_bytes = grown;
  }
  return tmp;
}

std::uint32_t* CudaExec::scratch_u32(std::size_t n) {
  if (n > scratch_n) {
    const std::size_t grown = std::max(n, 2 * scratch_n);
    void* p = nullptr;
    cuda_check(cudaMalloc(&p, grown * sizeof(std::uint32_t)), "scratch alloc");
    if (scratch) outgrown.push_back(scratch);
    scratch = static_cast<std::uint32_t*>(p);
    scratch_n = grown;
  }
  return scratch;
}

std::uint32_t exclusive_scan(CudaExec& ex, const std::uint32_t* in, std::uint32_t* out, int n) {
  if (n <= 0) return 0;
  std::uint32_t last_in = 0, last_out = 0;
  cuda_check(cudaMemcpyAsync(&last_in, in + n - 1, 4, cudaMemcpyDeviceToHost, ex.stream), "scan");
  std::size_t bytes = 0;
  cuda_check(cub::DeviceScan::ExclusiveSum(nullptr, bytes, in, out, n, ex.stream), "cub scan");
  cuda_check(cub::DeviceScan::ExclusiveSum(ex.temp(bytes), bytes, in, out, n, ex.stream),
             "cub scan");
  cuda_check(cudaMemcpyAsync(&last_out, out + n - 1, 4, cudaMemcpyDeviceToHost, ex.stream), "scan");
  cuda_check(cudaStreamSynchronize(ex.stream), "scan");
  return last_in + last_out;
}

void sort_pairs(CudaExec& ex, std::uint32_t* keys, std::uint32_t* vals, int n, int key_bits) {
  if (n <= 1) return;
  std::uint32_t* alt = ex.scratch_u32(2 * std::size_t(n));
  cub::DoubleBuffer<std::uint32_t> k(keys, alt), v(vals, alt + n);
  std::size_t bytes = 0;
  cuda_check(cub::DeviceRadixSort::SortPairs(nullptr, bytes, k, v, n, 0, key_bits, ex.stream),
             "cub sort");
  cuda_check(
      cub::DeviceRadixSort::SortPairs(ex.temp(bytes), bytes, k, v, n, 0, key_bits, ex.stream),
      "cub sort");
  if (k.Current() != keys)
    cuda_check(
        cudaMemcpyAsync(keys, k.Current(), 4 * std::size_t(n), cudaMemcpyDeviceToDevice, ex.stream),
        "sort");
  if (v.Current() != vals)
    cuda_check(
        cudaMemcpyAsync(vals, v.Current(), 4 * std::size_t(n), cudaMemcpyDeviceToDevice, ex.stream),
        "sort");
}

// Device memory for Buffer<T> (memory.h).
void* device_alloc(std::size_t bytes) {
  void* p = nullptr;
  cuda_check(cudaMalloc(&p, bytes), "cudaMalloc");
  return p;
}
void device_free(void* p) { cudaFree(p); }
void device_copy(void* dst, bool dst_device, const void* src, bool src_device, std::size_t n) {
  const cudaMemcpyKind kind = dst_device
                                  ? (src_device ? cudaMemcpyDeviceToDevice : cudaMemcpyHostToDevice)
                                  : cudaMemcpyDeviceToHost;
  cuda_check(cudaMemcpy(dst, src, n, kind), "cudaMemcpy");
}
void device_zero(void* p, std::size_t bytes) { cuda_check(cudaMemset(p, 0, bytes), "cudaMemset"); }

bool cuda_available(std::string* why) {
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess || count == 0) {
    if (why)
      *why = e != cudaSuccess ? std::string("no usable CUDA device: ") + cudaGetErrorString(e)
                              : std::string("no CUDA device found");
    return false;
  }
  return true;
}

}  // namespace sphfem
