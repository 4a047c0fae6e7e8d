#include <stdexcept>

#include "sphfem/sph/solver.h"

namespace sphfem {

std::unique_ptr<FluidSolver> make_cuda_fluid_solver(const FluidModel&) {
  throw std::runtime_error("this build of sphfem has no CUDA backend; use --backend cpu");
}

}  // namespace sphfem
