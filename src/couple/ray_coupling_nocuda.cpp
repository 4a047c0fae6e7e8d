#include <stdexcept>

#include "sphfem/couple/ray_coupling.h"

namespace sphfem {

std::unique_ptr<RayCoupling> make_cuda_ray_coupling(const RayCouplingSettings&, BodySolver*) {
  throw std::runtime_error("this build of sphfem has no CUDA backend; use --backend cpu");
}

}  // namespace sphfem
