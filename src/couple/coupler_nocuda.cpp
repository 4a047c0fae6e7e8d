#include <stdexcept>

#include "sphfem/couple/coupler.h"

namespace sphfem {

std::unique_ptr<Coupler> make_cuda_coupler() {
  throw std::runtime_error("this build of sphfem has no CUDA backend; use --backend cpu");
}

}  // namespace sphfem
