// The CUDA instantiation of the ray-traced coupling hook: the same code as the CPU's.
#include "core/exec_cuda.cuh"
#include "couple/ray_coupling_impl.h"

namespace sphfem {

std::unique_ptr<RayCoupling> make_cuda_ray_coupling(const RayCouplingSettings& settings,
                                                    BodySolver* bodies) {
  return std::make_unique<RayCouplingT<CudaExec>>(settings, bodies, Backend::Cuda);
}

}  // namespace sphfem
