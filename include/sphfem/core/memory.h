// Buffers that live on the host or on a CUDA device. CUDA types stay out of this header;
// the device functions are defined in src/core/memory_cuda.cu (or report that CUDA is absent).
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace sphfem {

enum class MemSpace { Host, Device };

void* mem_alloc(MemSpace space, std::size_t bytes);
void mem_free(MemSpace space, void* p);
void mem_copy(MemSpace dst_space, void* dst, MemSpace src_space, const void* src,
              std::size_t bytes);
void mem_zero(MemSpace space, void* p, std::size_t bytes);

// A typed array in one memory space. Resizing keeps the first min(old, new) elements.
template <class T>
class Buffer {
 public:
  explicit Buffer(MemSpace space = MemSpace::Host) : space_(space) {}
  Buffer(MemSpace space, std::size_t n) : space_(space) { resize(n); }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  Buffer(Buffer&& o) noexcept { swap(o); }
  Buffer& operator=(Buffer&& o) noexcept {
    swap(o);
    return *this;
  }
  ~Buffer() { mem_free(space_, data_); }

  void swap(Buffer& o) noexcept {
    std::swap(space_, o.space_);
    std::swap(data_, o.data_);
    std::swap(size_, o.size_);
    std::swap(capacity_, o.capacity_);
  }
  void reserve(std::size_t n) {
    if (n <= capacity_) return;
    T* p = static_cast<T*>(mem_alloc(space_, n * sizeof(T)));
    if (size_) mem_copy(space_, p, space_, data_, size_ * sizeof(T));
    mem_free(space_, data_);
    data_ = p;
    capacity_ = n;
  }
  void resize(std::size_t n) {
    reserve(n);
    size_ = n;
  }
  void zero() {
    if (size_) mem_zero(space_, data_, size_ * sizeof(T));
  }
  void upload(const T* host, std::size_t n, std::size_t offset = 0) {
    mem_copy(space_, data_ + offset, MemSpace::Host, host, n * sizeof(T));
  }
  void download(T* host, std::size_t n, std::size_t offset = 0) const {
    mem_copy(MemSpace::Host, host, space_, data_ + offset, n * sizeof(T));
  }
  // The first n values into a host vector of exactly that length.
  void download(std::vector<T>& host, std::size_t n) const {
    host.resize(n);
    download(host.data(), n);
  }
  T* data() { return data_; }
  const T* data() const { return data_; }
  std::size_t size() const { return size_; }
  MemSpace space() const { return space_; }

 private:
  MemSpace space_ = MemSpace::Host;
  T* data_ = nullptr;
  std::size_t size_ = 0;
  std::size_t capacity_ = 0;
};

}  // namespace sphfem
