// The CUDA instantiation of the body solver: the same stages as the CPU, run as kernels.
#include "core/exec_cuda.cuh"
#include "fem/solver_impl.h"

namespace sphfem {

std::unique_ptr<BodySolver> make_cuda_body_solver(std::shared_ptr<const BodiesModel> model) {
  return std::make_unique<BodySolverT<CudaExec>>(std::move(model));
}

}  // namespace sphfem
