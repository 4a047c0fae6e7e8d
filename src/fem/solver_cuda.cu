// The CUDA instantiation of the body solver: the same stages as the CPU, run as kernels.
#include "core/exec_cuda.cuh"
#include "fem/solver_impl.h"

namespace sphfem {

std::unique_ptr<BodySolver> make_cuda_body_solver(const BodiesModel& model) {
  return std::make_unique<BodySolverT<CudaExec>>(model);
}

}  // namespace sphfem
