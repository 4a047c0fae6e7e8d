// Atomic accumulation usable in parallel_for bodies on every backend: atomicAdd on the device,
// an OpenMP atomic on the host. For sums whose writers cannot be grouped by target (coupling
// impulses on nodes shared by several faces); gather lists stay preferable where they exist.
#pragma once

#include "sphfem/core/vec.h"

namespace sphfem {

SPHFEM_HD void atomic_add(Real* p, Real v) {
#if defined(__CUDA_ARCH__)
  atomicAdd(p, v);
#else
#pragma omp atomic
  *p += v;
#endif
}

// Three independent atomics: a reader that races with the writers may see some components
// updated and others not, but the sums are exact once the loop ends.
SPHFEM_HD void atomic_add(Vec3* p, const Vec3& v) {
  atomic_add(&p->x, v.x);
  atomic_add(&p->y, v.y);
  atomic_add(&p->z, v.z);
}

}  // namespace sphfem
