// The CPU instantiation of the solver, and the backend factory.
#include "core/exec_cpu.h"
#include "sph/solver_impl.h"

namespace sphfem {

std::unique_ptr<FluidSolver> make_cuda_fluid_solver(const FluidModel& model);

std::unique_ptr<FluidSolver> make_fluid_solver(const FluidModel& model, Backend backend) {
  if (backend == Backend::Cuda) {
    std::string why;
    if (!cuda_available(&why))
      throw std::runtime_error("--backend cuda: " + why + "; run with --backend cpu");
    return make_cuda_fluid_solver(model);
  }
  return std::make_unique<SolverT<CpuExec>>(model);
}

}  // namespace sphfem
