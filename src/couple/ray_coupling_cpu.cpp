// The CPU instantiation of the ray-traced coupling hook and its backend factory.
#include "core/exec_cpu.h"
#include "couple/ray_coupling_impl.h"

namespace sphfem {

std::unique_ptr<RayCoupling> make_cuda_ray_coupling(const RayCouplingSettings& settings,
                                                    BodySolver* bodies);

std::unique_ptr<RayCoupling> make_ray_coupling(const RayCouplingSettings& settings,
                                               BodySolver* bodies, Backend backend) {
  if (backend == Backend::Cuda) {
    std::string why;
    if (!cuda_available(&why))
      throw std::runtime_error("--backend cuda: " + why + "; run with --backend cpu");
    return make_cuda_ray_coupling(settings, bodies);
  }
  return std::make_unique<RayCouplingT<CpuExec>>(settings, bodies, Backend::Cpu);
}

}  // namespace sphfem
