// The CPU instantiation of the body solver, and the backend factory.
#include "core/exec_cpu.h"
#include "fem/solver_impl.h"

namespace sphfem {

std::unique_ptr<BodySolver> make_cuda_body_solver(std::shared_ptr<const BodiesModel> model);

std::unique_ptr<BodySolver> make_body_solver(const BodiesModel& model, Backend backend) {
  return make_body_solver(std::make_shared<const BodiesModel>(model), backend);
}

std::unique_ptr<BodySolver> make_body_solver(std::shared_ptr<const BodiesModel> model,
                                             Backend backend) {
  if (backend == Backend::Cuda) {
    std::string why;
    if (!cuda_available(&why))
      throw std::runtime_error("--backend cuda: " + why + "; run with --backend cpu");
    return make_cuda_body_solver(std::move(model));
  }
  return std::make_unique<BodySolverT<CpuExec>>(std::move(model));
}

}  // namespace sphfem
