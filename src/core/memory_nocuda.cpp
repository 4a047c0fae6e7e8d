// Device memory when the library is built without CUDA: every use is an error that says so.
#include <stdexcept>
#include <string>

#include "sphfem/core/backend.h"

namespace sphfem {

namespace {
[[noreturn]] void no_cuda() {
  throw std::runtime_error(
      "this build of sphfem has no CUDA backend; rebuild with -DSPHFEM_ENABLE_CUDA=ON "
      "where nvcc is installed, or use --backend cpu");
}
}  // namespace

void* device_alloc(std::size_t) { no_cuda(); }
void device_free(void*) {}
void device_copy(void*, bool, const void*, bool, std::size_t) { no_cuda(); }
void device_zero(void*, std::size_t) { no_cuda(); }

std::string cuda_device_name() { return "no CUDA backend"; }

bool cuda_available(std::string* why) {
  if (why)
    *why = "this build of sphfem has no CUDA backend (configured with SPHFEM_ENABLE_CUDA=OFF)";
  return false;
}

}  // namespace sphfem
