// The GPU's name for result files and logs (include/sphfem/core/backend.h).
#include <cuda_runtime.h>

#include <string>

#include "sphfem/core/backend.h"

namespace sphfem {

std::string cuda_device_name() {
  int device = 0;
  cudaDeviceProp prop;
  if (cudaGetDevice(&device) != cudaSuccess ||
      cudaGetDeviceProperties(&prop, device) != cudaSuccess)
    return "CUDA device";
  return prop.name;
}

}  // namespace sphfem
