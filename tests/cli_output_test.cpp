// Output that cannot be written: a read-only folder, a full disk (/dev/full behind a frame's
// temporary name), a file-size limit (ulimit -f). The run stops at once with exit code 4 and a
// message naming the file, keeps every frame already written, and leaves no half-written file.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string>

#include "cli_harness.h"
#include "sphfem/io/vtu.h"

namespace {

namespace fs = std::filesystem;
using sphfem::testing_cli::cli;
using sphfem::testing_cli::Result;

// Frames grow as the emitter pours: about 16 kB at the start, 60 kB after 0.1 s.
const char* kScene = R"({
  "simulation": {"duration": 0.1, "solver": "dfsph", "dt_max": 0.002},
  "domain": {"min": [0, 0, 0], "max": [0.2, 0.2, 0.1]},
  "fluid": {"particle_radius": 0.0025, "blocks": [{"min": [0, 0, 0], "max": [0.1, 0.02, 0.02]}],
            "emitters": [{"position": [0.1, 0.15, 0.05], "direction": [0, -1, 0],
                          "radius": 0.02, "speed": 1}]},
  "output": {"fps": 100}
})";

class CliOutput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("sphfem_output_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
    scene_ = (dir_ / "scene.json").string();
    std::ofstream(scene_) << kScene;
  }
  void TearDown() override {
    std::error_code ec;
    fs::permissions(dir_ / "ro", fs::perms::owner_all, ec);
    fs::remove_all(dir_, ec);
  }

  // What every stopped run must leave: whole frames that read back, no temporaries, gauge rows
  // all complete. Returns the number of fluid frames.
  int check_left_whole(const fs::path& out) {
    int frames = 0;
    for (const auto& e : fs::recursive_directory_iterator(out)) {
      const std::string name = e.path().filename().string();
      EXPECT_NE(e.path().extension(), ".tmp") << "a temporary was left: " << e.path();
      if (name.rfind("fluid_", 0) == 0 && e.path().extension() == ".vtu") {
        EXPECT_NO_THROW(sphfem::io::read_vtu(e.path().string())) << e.path();
        ++frames;
      }
    }
    std::ifstream g(out / "gauges.csv", std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(g)), std::istreambuf_iterator<char>());
    EXPECT_FALSE(text.empty());
    EXPECT_EQ(text.back(), '\n') << "gauges.csv ends in half a row";
    std::istringstream lines(text);
    std::string header, row;
    std::getline(lines, header);
    const auto columns = std::count(header.begin(), header.end(), ',');
    int rows = 0;
    while (std::getline(lines, row)) {
      EXPECT_EQ(std::count(row.begin(), row.end(), ','), columns) << row;
      ++rows;
    }
    EXPECT_EQ(rows, frames) << "one gauge row per frame kept";
    return frames;
  }

  fs::path dir_;
  std::string scene_;
};

TEST_F(CliOutput, ReadOnlyFolderStopsBeforeTheFirstStep) {
  const fs::path ro = dir_ / "ro";
  fs::create_directories(ro);
  fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
  // Root writes into a read-only folder anyway; /proc refuses new folders even to root.
  const fs::path out = geteuid() == 0 ? fs::path("/proc/sphfem_out") : ro / "out";
  const Result r = cli("run " + scene_ + " --quiet --out " + out.string());
  EXPECT_EQ(r.code, 4) << r.out;
  EXPECT_NE(r.out.find("cannot create folder '" + (out / "frames").string() + "'"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("give --out a folder you can write to"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("steps"), std::string::npos) << "it stopped before stepping: " << r.out;
}

TEST_F(CliOutput, FullDiskAtAFrameKeepsTheFramesBefore) {
  // Frame 4's temporary is /dev/full: its write fails with ENOSPC as on a full disk.
  const fs::path out = dir_ / "out";
  fs::create_directories(out / "frames");
  fs::create_symlink("/dev/full", out / "frames" / "fluid_000004.vtu.tmp");
  const Result r = cli("run " + scene_ + " --quiet --out " + out.string());
  EXPECT_EQ(r.code, 4) << r.out;
  EXPECT_NE(r.out.find("fluid_000004.vtu': No space left on device"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("frames written so far are kept in " + out.string()), std::string::npos)
      << r.out;
  EXPECT_EQ(check_left_whole(out), 4);
  EXPECT_FALSE(fs::exists(out / "frames" / "fluid_000004.vtu"));
  EXPECT_FALSE(fs::exists(out / "checkpoint.bin")) << "no checkpoint of a run that stopped";
}

TEST_F(CliOutput, FileSizeLimitStopsTheRunWithAMessage) {
  // ulimit -f 32: no file may pass 32 KiB. Without SIGXFSZ ignored the signal would kill the
  // run silently; the growing frames pass the limit after a few.
  const fs::path out = dir_ / "out";
  const Result r = cli("run " + scene_ + " --quiet --out " + out.string(),
                       "bash -c 'ulimit -f 32 && exec \"$0\" \"$@\"'");
  EXPECT_EQ(r.code, 4) << r.out;
  EXPECT_NE(r.out.find("File too large"), std::string::npos) << r.out;
  const int frames = check_left_whole(out);
  EXPECT_GE(frames, 1);
  EXPECT_LT(frames, 11) << "the run did not stop";
}

}  // namespace
