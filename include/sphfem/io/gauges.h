// Time series of measured quantities (probes, energies, forces) as a CSV file.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

namespace sphfem::io {

// Writes a header line at construction and one line per row(); every line is flushed to the
// OS at once so a crashed run keeps all rows written before the crash.
class GaugeWriter {
 public:
  // Truncates `path`; throws std::runtime_error naming the path (and a missing folder).
  GaugeWriter(const std::string& path, std::vector<std::string> columns);
  ~GaugeWriter();
  GaugeWriter(const GaugeWriter&) = delete;
  GaugeWriter& operator=(const GaugeWriter&) = delete;
  GaugeWriter(GaugeWriter&& o) noexcept;
  GaugeWriter& operator=(GaugeWriter&& o) noexcept;

  // One value per column (else std::invalid_argument). Integral values below 1e15 print as
  // integers, others with "%.9g".
  void row(const std::vector<double>& values);

  const std::string& path() const { return path_; }
  const std::vector<std::string>& columns() const { return columns_; }

 private:
  void put(const std::string& line);

  std::string path_;
  std::vector<std::string> columns_;
  std::FILE* file_ = nullptr;
};

// The text one value takes in a gauge file.
std::string format_gauge_value(double v);

}  // namespace sphfem::io
