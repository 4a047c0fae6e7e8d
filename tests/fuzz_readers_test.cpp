// Every reader of outside data under seeded mutations of its seed files (fuzz/readers.h): each
// input must be read or refused with the reader's documented one-line error naming the file,
// within a time limit. The inputs that once found a defect are read first, from
// tests/data/fuzz/<reader>/crash_*.
//
// SPHFEM_FUZZ_INPUTS (default 2000) and SPHFEM_FUZZ_SECONDS (default 6) bound each reader's run;
// SPHFEM_FUZZ_SLOW (default 10 s) is the time an input may take before it counts as a hang: an
// input takes milliseconds, but ctest runs the heavy physics tests beside this one, and under
// that load a 3 KB input was measured at 3.7 s.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "fuzz_mutator.h"
#include "readers.h"

namespace sphfem::fuzz {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double env_or(const char* name, double fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::atof(v) : fallback;
}

Bytes slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class FuzzReaders : public ::testing::TestWithParam<Reader> {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("sphfem_fuzz_" + std::string(reader_name(GetParam())) +
                                        "_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  // Reads one input; a defect or a hang fails the test with the input kept beside the build.
  bool read_one(const Bytes& input, const std::string& what) {
    // A crash kills the test binary: the input it was reading is left in the working folder.
    const fs::path last =
        fs::current_path() / ("fuzz_last_" + std::string(reader_name(GetParam())));
    std::ofstream(last, std::ios::binary) << input;
    const auto t0 = Clock::now();
    std::string defect;
    try {
      read_input(GetParam(), reinterpret_cast<const std::uint8_t*>(input.data()), input.size(),
                 (dir_ / "in").string());
    } catch (const FuzzDefect& e) { defect = e.what(); }
    const double s = std::chrono::duration<double>(Clock::now() - t0).count();
    std::error_code ec;
    fs::remove(last, ec);
    if (defect.empty() && s > env_or("SPHFEM_FUZZ_SLOW", 10.0))
      defect = "took " + std::to_string(s) + " s";
    if (defect.empty()) return true;
    const fs::path keep =
        fs::current_path() / ("fuzz_failure_" + std::string(reader_name(GetParam())));
    std::ofstream(keep, std::ios::binary) << input;
    ADD_FAILURE() << reader_name(GetParam()) << " " << what << ": " << defect
                  << "\n(the input is in " << keep.string() << ")";
    return false;
  }

  fs::path dir_;
};

TEST_P(FuzzReaders, SeedsAndPastFindingsAreReadCleanly) {
  const Reader r = GetParam();
  const std::vector<std::string> seeds = seed_files(r, SPHFEM_SOURCE_DIR);
  ASSERT_FALSE(seeds.empty()) << "no seeds in tests/data/fuzz/" << reader_name(r);
  for (const std::string& s : seeds) read_one(slurp(s), s);
  const fs::path dir = fs::path(SPHFEM_SOURCE_DIR) / "tests/data/fuzz" / reader_name(r);
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().rfind("crash_", 0) == 0)
      read_one(slurp(e.path().string()), e.path().string());
}

TEST_P(FuzzReaders, SeededMutationsAreReadOrRefusedCleanly) {
  const Reader r = GetParam();
  std::vector<Bytes> seeds;
  for (const std::string& s : seed_files(r, SPHFEM_SOURCE_DIR)) seeds.push_back(slurp(s));
  ASSERT_FALSE(seeds.empty());
  Mutator m(0x5eed0000u + unsigned(r), seeds);
  const long inputs = long(env_or("SPHFEM_FUZZ_INPUTS", 2000));
  const double budget = env_or("SPHFEM_FUZZ_SECONDS", 6.0);
  const auto t0 = Clock::now();
  long done = 0, failures = 0;
  for (; done < inputs; ++done) {
    if (std::chrono::duration<double>(Clock::now() - t0).count() > budget) break;
    if (!read_one(m.next(), "mutation " + std::to_string(done)) && ++failures >= 3) break;
  }
  std::printf("%s: %ld inputs in %.1f s\n", reader_name(r), done,
              std::chrono::duration<double>(Clock::now() - t0).count());
  // A run that reads almost nothing proves nothing.
  EXPECT_GE(done, std::min<long>(inputs, 200));
}

INSTANTIATE_TEST_SUITE_P(Readers, FuzzReaders, ::testing::ValuesIn(all_readers()),
                         [](const ::testing::TestParamInfo<Reader>& i) {
                           std::string n = reader_name(i.param);
                           n.erase(std::remove(n.begin(), n.end(), '_'), n.end());
                           return n;
                         });

}  // namespace
}  // namespace sphfem::fuzz
