#include <stdexcept>

#include "sphfem/fem/solver.h"

namespace sphfem {

std::unique_ptr<BodySolver> make_cuda_body_solver(std::shared_ptr<const BodiesModel>) {
  throw std::runtime_error("this build of sphfem has no CUDA backend; use --backend cpu");
}

}  // namespace sphfem
