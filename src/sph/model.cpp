// The particle mass that gives a full lattice its rest density (kernel sum over the lattice).
#include "sphfem/sph/model.h"

#include <cmath>

namespace sphfem {

Real lattice_mass(const Kernel& kernel, Real spacing, Real rho0) {
  const int r = int(std::ceil(kernel.cubic.h / spacing)) + 1;
  double sum = 0;
  for (int i = -r; i <= r; ++i)
    for (int j = -r; j <= r; ++j)
      for (int k = -r; k <= r; ++k)
        sum += kernel.W(Real(spacing * std::sqrt(double(i * i + j * j + k * k))));
  return Real(double(rho0) / sum);
}

}  // namespace sphfem
