// Which execution backend runs a simulation, and whether it is usable on this machine.
#pragma once

#include <string>

namespace sphfem {

enum class Backend { Cpu, Cuda };

// True when the library was built with CUDA and a device is present; otherwise `why` says
// what is missing.
bool cuda_available(std::string* why);

// Number of CPU threads the CPU backend uses; 0 = all cores.
void set_cpu_threads(int n);
int cpu_threads();

}  // namespace sphfem
