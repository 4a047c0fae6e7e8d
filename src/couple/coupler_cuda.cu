// The CUDA instantiation of the coupler: the same stages as the CPU, run as kernels.
#include "core/exec_cuda.cuh"
#include "couple/coupler_impl.h"

namespace sphfem {

std::unique_ptr<Coupler> make_cuda_coupler() { return std::make_unique<CouplerT<CudaExec>>(); }

}  // namespace sphfem
