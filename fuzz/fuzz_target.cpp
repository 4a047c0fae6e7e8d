// libFuzzer entry for one reader, chosen at build time (SPHFEM_FUZZ_READER, its name in
// fuzz/readers.h). A defect is an uncaught FuzzDefect, so libFuzzer reports it as a crash and
// keeps the input; sanitizer reports and hangs are its own.
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>

#include "readers.h"

namespace {

sphfem::fuzz::Reader chosen() {
  for (sphfem::fuzz::Reader r : sphfem::fuzz::all_readers())
    if (std::strcmp(sphfem::fuzz::reader_name(r), SPHFEM_FUZZ_READER) == 0) return r;
  __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string dir =
      (std::filesystem::temp_directory_path() / ("sphfem_fuzz_" + std::to_string(getpid())))
          .string();
  sphfem::fuzz::read_input(chosen(), data, size, dir);
  return 0;
}
