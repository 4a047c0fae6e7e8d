// The CPU instantiation of the BVH and its queries, and the Collider factory.
#include "collide/collider_impl.h"
#include "core/exec_cpu.h"

namespace sphfem {

SPHFEM_INSTANTIATE_COLLIDE(CpuExec)

std::unique_ptr<Collider> make_cuda_collider();

std::unique_ptr<Collider> make_collider(Backend backend) {
  if (backend == Backend::Cuda) {
    std::string why;
    if (!cuda_available(&why))
      throw std::runtime_error("collide on CUDA: " + why + "; use the CPU backend");
    return make_cuda_collider();
  }
  return std::make_unique<ColliderT<CpuExec>>();
}

}  // namespace sphfem
