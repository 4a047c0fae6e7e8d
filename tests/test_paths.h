// Where the tests find this checkout's scenes and data, and the CLI: the paths this build was
// configured with, unless SPHFEM_SOURCE_DIR or SPHFEM_CLI in the environment say otherwise (a
// test binary carried to another machine: scripts/gpu-check.sh). Included in every test file
// by tests/CMakeLists.txt.
#pragma once

#include <cstdlib>

namespace sphfem_test {

inline const char* env_or(const char* name, const char* built) {
  const char* e = std::getenv(name);
  return e && *e ? e : built;
}

}  // namespace sphfem_test

#define SPHFEM_SOURCE_DIR ::sphfem_test::env_or("SPHFEM_SOURCE_DIR", SPHFEM_BUILT_SOURCE_DIR)
#define SPHFEM_CLI ::sphfem_test::env_or("SPHFEM_CLI", SPHFEM_BUILT_CLI)
