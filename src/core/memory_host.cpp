#include <cstdlib>
#include <cstring>
#include <new>

#include "sphfem/core/memory.h"

namespace sphfem {

void* device_alloc(std::size_t bytes);
void device_free(void* p);
void device_copy(void* dst, bool dst_device, const void* src, bool src_device, std::size_t n);
void device_zero(void* p, std::size_t bytes);

void* mem_alloc(MemSpace space, std::size_t bytes) {
  if (bytes == 0) return nullptr;
  if (space == MemSpace::Device) return device_alloc(bytes);
  // 64-byte alignment keeps SoA arrays friendly to vector loads.
  void* p = std::aligned_alloc(64, (bytes + 63) / 64 * 64);
  if (!p) throw std::bad_alloc();
  return p;
}

void mem_free(MemSpace space, void* p) {
  if (!p) return;
  if (space == MemSpace::Device)
    device_free(p);
  else
    std::free(p);
}

void mem_copy(MemSpace dst_space, void* dst, MemSpace src_space, const void* src,
              std::size_t bytes) {
  if (bytes == 0) return;
  if (dst_space == MemSpace::Host && src_space == MemSpace::Host)
    std::memmove(dst, src, bytes);
  else
    device_copy(dst, dst_space == MemSpace::Device, src, src_space == MemSpace::Device, bytes);
}

void mem_zero(MemSpace space, void* p, std::size_t bytes) {
  if (space == MemSpace::Device)
    device_zero(p, bytes);
  else
    std::memset(p, 0, bytes);
}

}  // namespace sphfem
