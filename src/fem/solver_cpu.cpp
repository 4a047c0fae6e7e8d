// The CPU instantiation of the body solver, and the backend factory.
#include "core/exec_cpu.h"
#include "fem/solver_impl.h"

namespace sphfem {

std::unique_ptr<BodySolver> make_cuda_body_solver(const BodiesModel& model);

std::unique_ptr<BodySolver> make_body_solver(const BodiesModel& model, Backend backend) {
  if (backend == Backend::Cuda) {
    std::string why;
    if (!cuda_available(&why))
      throw std::runtime_error("--backend cuda: " + why + "; run with --backend cpu");
    return make_cuda_body_solver(model);
  }
  return std::make_unique<BodySolverT<CpuExec>>(model);
}

}  // namespace sphfem
