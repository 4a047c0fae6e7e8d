// Frame files are little endian; these helpers keep them so on any host.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace sphfem::io {

inline bool host_is_little_endian() {
  const std::uint16_t one = 1;
  unsigned char first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

// Copies n elements of `size` bytes each between host order and little-endian order (the
// same operation both ways): a plain copy on little-endian hosts, a byte reversal otherwise.
inline void copy_le(void* dst, const void* src, std::size_t n, std::size_t size) {
  if (host_is_little_endian() || size == 1) {
    if (n) std::memcpy(dst, src, n * size);
    return;
  }
  auto* d = static_cast<unsigned char*>(dst);
  const auto* s = static_cast<const unsigned char*>(src);
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t b = 0; b < size; ++b) d[k * size + b] = s[k * size + size - 1 - b];
}

}  // namespace sphfem::io
