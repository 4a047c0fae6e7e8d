#include <stdexcept>

#include "sphfem/collide/collider.h"

namespace sphfem {

std::unique_ptr<Collider> make_cuda_collider() {
  throw std::runtime_error("this build of sphfem has no CUDA backend; use the CPU backend");
}

}  // namespace sphfem
