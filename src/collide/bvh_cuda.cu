// The CUDA instantiation of the BVH and its queries: the same code as the CPU, as kernels.
#include "collide/collider_impl.h"
#include "core/exec_cuda.cuh"

namespace sphfem {

SPHFEM_INSTANTIATE_COLLIDE(CudaExec)

std::unique_ptr<Collider> make_cuda_collider() { return std::make_unique<ColliderT<CudaExec>>(); }

}  // namespace sphfem
