// Which execution backend runs a simulation, and whether it is usable on this machine.
#pragma once

#include <string>

namespace sphfem {

enum class Backend { Cpu, Cuda };

// True when the library was built with CUDA and a device is present; otherwise `why` says
// what is missing.
bool cuda_available(std::string* why);
// The name of the GPU the CUDA backend runs on (for result files).
std::string cuda_device_name();

// The stage a GPU error is reported in: Simulation names each stage of a step while it runs
// (nullptr outside one). Kernel faults surface at a later synchronisation; with
// SPHFEM_CUDA_CHECK=1 in the environment every launch is synchronised and checked, so the
// error names the stage and the source line that launched the failing kernel.
void set_stage_label(const char* label);
const char* stage_label();

// Number of CPU threads the CPU backend uses; 0 = all cores.
void set_cpu_threads(int n);
int cpu_threads();

}  // namespace sphfem
