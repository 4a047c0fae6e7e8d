// Checkpoint and resume through the sphfem command: a run split by a checkpoint, or killed
// with SIGKILL mid-step, ends in the same state (hash) with the same gauge rows as a straight
// run; damaged or foreign checkpoints each give their error and leave the folder as it was.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_harness.h"

namespace fs = std::filesystem;

namespace {

using sphfem::testing_cli::cli;
using sphfem::testing_cli::Result;

std::string hash_of(const std::string& out) {
  const std::size_t at = out.find("state hash ");
  return at == std::string::npos ? "" : out.substr(at + 11, 16);
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The gauge rows without the timing columns (ms_*), which measure the machine, not the run.
std::vector<std::string> rows_without_timings(const fs::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<bool> keep;
  std::stringstream header(line);
  for (std::string c; std::getline(header, c, ',');) keep.push_back(c.rfind("ms_", 0) != 0);
  std::vector<std::string> rows;
  while (std::getline(in, line)) {
    std::stringstream row(line);
    std::string kept;
    std::size_t k = 0;
    for (std::string v; std::getline(row, v, ','); ++k)
      if (k < keep.size() && keep[k]) kept += v + ",";
    rows.push_back(kept);
  }
  return rows;
}

// A small soft cup under a nozzle: every part of the step runs (emitter, near-surface density,
// rays, exact contact fix, exchange, FEM).
const char* kScene = R"({
  "simulation": { "duration": 0.3, "solver": "dfsph", "dt_max": 0.002 },
  "fluid": { "particle_radius": 0.006, "viscosity": 1e-5,
             "emitters": [ { "position": [0.2, 0.2, 0.2], "direction": [0, -1, 0],
                             "radius": 0.02, "speed": 1.0, "end": 0.25 } ] },
  "domain": { "min": [0, 0, 0], "max": [0.4, 0.4, 0.4] },
  "bodies": [ { "name": "cup", "shape": "cup", "position": [0.2, 0.0005, 0.2], "radius": 0.09,
                "inner_radius": 0.07, "height": 0.15, "thickness": 0.02, "resolution": 6,
                "material": { "density": 1100, "young": 3e5, "poisson": 0.4,
                              "damping_alpha": 1.0, "damping_beta": 0.002 },
                "pinned": { "boxes": [ { "min": [0.1, 0, 0.1], "max": [0.3, 0.001, 0.3] } ] } } ],
  "output": { "fps": 40, "checkpoint_every": CHECKPOINT_EVERY },
  "gauges": [ { "name": "rim", "type": "node", "body": "cup", "position": [0.29, 0.15, 0.2] } ]
})";

class Resume : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("sphfem_resume_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string scene(const std::string& every, const std::string& name = "cup.json") {
    std::string text = kScene;
    text.replace(text.find("CHECKPOINT_EVERY"), 16, every);
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  // The run in one go: its output (with the state hash) and its gauge rows.
  Result straight() {
    const fs::path out = dir_ / "straight";
    const Result r = cli("run " + scene("0", "straight.json") + " --out " + out.string() +
                         " --quiet --threads 2");
    straight_rows_ = rows_without_timings(out / "gauges.csv");
    return r;
  }
  std::vector<std::string> straight_rows_;
  fs::path dir_;
};

TEST_F(Resume, SplitRunMatchesStraightRunBitForBit) {
  const Result whole = straight();
  ASSERT_EQ(whole.code, 0) << whole.out;
  const std::string s = scene("0");
  const fs::path out = dir_ / "out";
  const Result first =
      cli("run " + s + " --out " + out.string() + " --quiet --duration 0.15 --threads 1");
  ASSERT_EQ(first.code, 0) << first.out;
  ASSERT_TRUE(fs::exists(out / "checkpoint.bin"));
  const Result rest = cli("run " + s + " --out " + out.string() + " --quiet --resume");
  ASSERT_EQ(rest.code, 0) << rest.out;
  EXPECT_EQ(hash_of(rest.out), hash_of(whole.out)) << whole.out << rest.out;
  EXPECT_FALSE(hash_of(whole.out).empty());
  EXPECT_EQ(rows_without_timings(out / "gauges.csv"), straight_rows_);
  // Every frame of the whole run is there, and the collection lists each once.
  EXPECT_TRUE(fs::exists(out / "frames" / "fluid_000012.vtu"));
  const std::string pvd = slurp(out / "fluid.pvd");
  EXPECT_EQ(pvd.find("fluid_000006.vtu"), pvd.rfind("fluid_000006.vtu"));
  EXPECT_NE(pvd.find("fluid_000012.vtu"), std::string::npos);
}

// Runs the scene into out and kills it with SIGKILL once it has written a checkpoint and
// gone on stepping; false when it finished first.
bool run_and_kill(const std::string& s, const fs::path& out,
                  const std::vector<std::string>& extra) {
  const pid_t pid = fork();
  if (pid < 0) return false;
  if (pid == 0) {
    const std::string cli_path = SPHFEM_CLI;
    std::freopen("/dev/null", "w", stdout);
    std::freopen("/dev/null", "w", stderr);
    std::vector<const char*> argv = {cli_path.c_str(), "run",       s.c_str(),
                                     "--out",          out.c_str(), "--quiet"};
    for (const std::string& a : extra) argv.push_back(a.c_str());
    argv.push_back(nullptr);
    execv(cli_path.c_str(), const_cast<char* const*>(argv.data()));
    _exit(127);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!fs::exists(out / "checkpoint.bin") && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::this_thread::sleep_for(std::chrono::milliseconds(40));
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  return !WIFEXITED(status);
}

TEST_F(Resume, RunKilledMidStepResumesFromItsLastCheckpoint) {
  const Result whole = straight();
  ASSERT_EQ(whole.code, 0) << whole.out;
  const std::string s = scene("0.05");
  const fs::path out = dir_ / "out";
  const bool killed = run_and_kill(s, out, {});
  ASSERT_TRUE(fs::exists(out / "checkpoint.bin"));
  if (!killed) GTEST_SKIP() << "the run finished before it could be killed";
  const Result rest = cli("run " + s + " --out " + out.string() + " --quiet --resume");
  ASSERT_EQ(rest.code, 0) << rest.out;
  EXPECT_EQ(hash_of(rest.out), hash_of(whole.out)) << rest.out;
  EXPECT_EQ(rows_without_timings(out / "gauges.csv"), straight_rows_);
}

// The interval given on the command line (as scripts/soak.sh does) instead of in the scene:
// the scene's identity leaves it out, so the run resumes with or without it.
TEST_F(Resume, CheckpointIntervalFromTheCommandLine) {
  const Result whole = straight();
  ASSERT_EQ(whole.code, 0) << whole.out;
  const std::string s = scene("0");
  const fs::path out = dir_ / "out";
  const bool killed = run_and_kill(s, out, {"--checkpoint-every", "0.05"});
  // Without the interval the first checkpoint is the run's last, and it ends before the kill.
  ASSERT_TRUE(killed) << "no checkpoint before the run's end";
  const Result rest = cli("run " + s + " --out " + out.string() + " --quiet --resume");
  ASSERT_EQ(rest.code, 0) << rest.out;
  EXPECT_EQ(hash_of(rest.out), hash_of(whole.out)) << rest.out;
  EXPECT_EQ(rows_without_timings(out / "gauges.csv"), straight_rows_);
  const Result zero = cli("run " + s + " --out " + out.string() + " --checkpoint-every 0");
  EXPECT_NE(zero.code, 0) << zero.out;
  EXPECT_NE(zero.out.find("--checkpoint-every"), std::string::npos) << zero.out;
}

TEST_F(Resume, DamagedOrForeignCheckpointsAreRefusedAndNothingIsLost) {
  const std::string s = scene("0");
  const fs::path out = dir_ / "out";
  ASSERT_EQ(cli("run " + s + " --out " + out.string() + " --quiet --duration 0.05").code, 0);
  const fs::path ck = out / "checkpoint.bin";
  const std::string good = slurp(ck);
  const std::string gauges = slurp(out / "gauges.csv");
  ASSERT_GT(good.size(), 64u);
  auto resume_with = [&](const std::string& bytes, const std::string& scene_path = "") {
    std::ofstream(ck, std::ios::binary) << bytes;
    return cli("run " + (scene_path.empty() ? s : scene_path) + " --out " + out.string() +
               " --quiet --resume");
  };
  struct Case {
    const char* what;
    std::string bytes;
    const char* says;
  };
  std::string flipped = good;
  flipped[flipped.size() / 2] ^= 0x10;
  std::string version = good;
  version[8] = 99;
  const std::vector<Case> cases = {
      {"truncated", good.substr(0, good.size() / 2), "truncated"},
      {"header only", good.substr(0, 20), "truncated"},
      {"bit flipped", flipped, "corrupted"},
      {"another version", version, "version 99"},
      {"not a checkpoint", "hello", "not a sphfem checkpoint"},
  };
  for (const Case& c : cases) {
    const Result r = resume_with(c.bytes);
    EXPECT_EQ(r.code, 2) << c.what << ": " << r.out;
    EXPECT_NE(r.out.find(ck.string()), std::string::npos) << c.what << ": " << r.out;
    EXPECT_NE(r.out.find(c.says), std::string::npos) << c.what << ": " << r.out;
    EXPECT_NE(r.out.find("without --resume"), std::string::npos) << c.what << ": " << r.out;
    EXPECT_EQ(slurp(out / "gauges.csv"), gauges) << c.what;
  }
  // The same file with a scene that differs in one value.
  std::string other_text = slurp(s);
  other_text.replace(other_text.find("\"speed\": 1.0"), 12, "\"speed\": 1.1");
  const fs::path other = dir_ / "other.json";
  std::ofstream(other) << other_text;
  const Result r = resume_with(good, other.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("another scene"), std::string::npos) << r.out;
  EXPECT_EQ(slurp(out / "gauges.csv"), gauges);
  // No checkpoint at all.
  fs::remove(ck);
  const Result none = cli("run " + s + " --out " + out.string() + " --quiet --resume");
  EXPECT_EQ(none.code, 2) << none.out;
  EXPECT_NE(none.out.find("no checkpoint"), std::string::npos) << none.out;
}

}  // namespace
