// Time-series outputs: the ParaView collection file and gauge CSV files.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "sphfem/io/gauges.h"
#include "sphfem/io/pvd.h"
#include "sphfem/io/xml.h"

namespace sphfem::io {
namespace {
namespace fs = std::filesystem;

class IoSeriesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("sphfem_io_" + std::string(info->test_suite_name()) + "_" +
                                        info->name() + "_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (std::size_t nl; (nl = text.find('\n', start)) != std::string::npos; start = nl + 1)
    out.push_back(text.substr(start, nl - start));
  EXPECT_EQ(start, text.size()) << "last line has no newline";
  return out;
}

struct DataSet {
  double time;
  std::string file;
};

std::vector<DataSet> datasets(const std::string& text) {
  std::vector<DataSet> out;
  for (std::size_t at = text.find("<DataSet "); at != std::string::npos;
       at = text.find("<DataSet ", at + 1)) {
    auto attrs = xml_attributes(text.substr(at + 1, text.find('>', at) - at - 1));
    out.push_back({std::strtod(attrs["timestep"].c_str(), nullptr), attrs["file"]});
  }
  return out;
}

TEST_F(IoSeriesTest, PvdListsFramesWithTimes) {
  PvdCollection pvd(file("fluid.pvd"));
  EXPECT_FALSE(fs::exists(file("fluid.pvd")));
  const std::vector<double> times = {0.0, 0.1, 0.2 + 1e-15, 1.0 / 3.0};
  for (std::size_t i = 0; i < times.size(); ++i) {
    pvd.add(times[i], "fluid/frame_" + std::to_string(i) + ".vtu");
    const std::string text = slurp(file("fluid.pvd"));
    EXPECT_EQ(text.rfind("<?xml", 0), 0u);
    EXPECT_NE(text.find("<VTKFile type=\"Collection\""), std::string::npos);
    const auto sets = datasets(text);
    ASSERT_EQ(sets.size(), i + 1);
    for (std::size_t k = 0; k <= i; ++k) {
      EXPECT_EQ(sets[k].time, times[k]);  // times read back exactly
      EXPECT_EQ(sets[k].file, "fluid/frame_" + std::to_string(k) + ".vtu");
    }
  }
  EXPECT_EQ(pvd.entries().size(), times.size());
  EXPECT_FALSE(fs::exists(file("fluid.pvd.tmp")));
}

TEST_F(IoSeriesTest, PvdEscapesFileNamesAndKeepsParts) {
  PvdCollection pvd(file("all.pvd"));
  pvd.add(0.5, "a&b.vtu");
  pvd.add(0.5, "wall.vtu", 1);
  const std::string text = slurp(file("all.pvd"));
  EXPECT_NE(text.find("file=\"a&amp;b.vtu\""), std::string::npos);
  EXPECT_NE(text.find("timestep=\"0.5\" group=\"\" part=\"1\" file=\"wall.vtu\""),
            std::string::npos);
  EXPECT_THROW(pvd.add(std::nan(""), "x.vtu"), std::invalid_argument);
}

TEST_F(IoSeriesTest, PvdFailureNamesPathAndKeepsEntries) {
  PvdCollection pvd(file("missing/fluid.pvd"));
  try {
    pvd.add(0.0, "f0.vtu");
    FAIL() << "expected a throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(file("missing/fluid.pvd")), std::string::npos);
  }
  EXPECT_TRUE(pvd.entries().empty());
  fs::create_directories(file("missing"));
  pvd.add(0.0, "f0.vtu");
  EXPECT_EQ(datasets(slurp(file("missing/fluid.pvd"))).size(), 1u);
}

TEST_F(IoSeriesTest, GaugeHeaderAndRows) {
  {
    GaugeWriter g(file("probe.csv"), {"time", "pressure", "step"});
    EXPECT_EQ(slurp(file("probe.csv")), "time,pressure,step\n");
    g.row({0.0, 101325.0, 0});
    g.row({0.1, 1.0 / 3.0, 12345678901234.0});
    // Rows are on disk while the writer is still open, as after a crash.
    EXPECT_EQ(lines(slurp(file("probe.csv"))).size(), 3u);
    g.row({-2.5e-7, 1e20, -3});
    g.row({std::nan(""), 1e15, 123456789.5});
  }
  const auto got = lines(slurp(file("probe.csv")));
  const std::vector<std::string> want = {"time,pressure,step", "0,101325,0",
                                         "0.1,0.333333333,12345678901234", "-2.5e-07,1e+20,-3",
                                         "nan,1e+15,123456790"};
  EXPECT_EQ(got, want);
}

TEST_F(IoSeriesTest, GaugeValueFormat) {
  EXPECT_EQ(format_gauge_value(42.0), "42");
  EXPECT_EQ(format_gauge_value(-999999999999999.0), "-999999999999999");
  EXPECT_EQ(format_gauge_value(0.125), "0.125");
  EXPECT_EQ(format_gauge_value(1.0 / 7.0), "0.142857143");
  EXPECT_EQ(format_gauge_value(1e-300), "1e-300");
  EXPECT_EQ(format_gauge_value(-HUGE_VAL), "-inf");
}

TEST_F(IoSeriesTest, GaugeWrongRowLengthThrows) {
  GaugeWriter g(file("g.csv"), {"a", "b"});
  EXPECT_THROW(g.row({1.0}), std::invalid_argument);
  EXPECT_THROW(g.row({1.0, 2.0, 3.0}), std::invalid_argument);
  g.row({1.0, 2.0});
  EXPECT_EQ(slurp(file("g.csv")), "a,b\n1,2\n");
  EXPECT_THROW(GaugeWriter(file("h.csv"), {}), std::invalid_argument);
}

TEST_F(IoSeriesTest, GaugeQuotesAwkwardColumnNames) {
  GaugeWriter g(file("g.csv"), {"t", "force, x", "say \"hi\""});
  EXPECT_EQ(slurp(file("g.csv")), "t,\"force, x\",\"say \"\"hi\"\"\"\n");
}

TEST_F(IoSeriesTest, GaugeMissingFolderIsClear) {
  const std::string path = file("nope/probe.csv");
  try {
    GaugeWriter g(path, {"t"});
    FAIL() << "expected a throw";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("does not exist"), std::string::npos) << msg;
  }
}

TEST_F(IoSeriesTest, GaugeWriterMoves) {
  GaugeWriter a(file("m.csv"), {"x"});
  GaugeWriter b = std::move(a);
  b.row({5});
  EXPECT_EQ(slurp(file("m.csv")), "x\n5\n");
}

}  // namespace
}  // namespace sphfem::io
