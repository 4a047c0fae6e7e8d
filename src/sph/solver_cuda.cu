// The CUDA instantiation of the solver: the same stages as the CPU, run as kernels.
#include "core/exec_cuda.cuh"
#include "sph/solver_impl.h"

namespace sphfem {

std::unique_ptr<FluidSolver> make_cuda_fluid_solver(const FluidModel& model) {
  return std::make_unique<SolverT<CudaExec>>(model);
}

}  // namespace sphfem
