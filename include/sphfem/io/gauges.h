// Time series of measured quantities (probes, energies, forces) as a CSV file.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

namespace sphfem::io {

// Writes a header line at construction and one line per row(); every line goes to the OS at
// once so a crashed run keeps all rows written before the crash, and a line that cannot be
// written whole (a full disk) is cut off again, so the file never ends in half a row.
class GaugeWriter {
 public:
  // Truncates `path`; throws WriteError (atomic_file.h) naming the path (and a missing folder).
  GaugeWriter(const std::string& path, std::vector<std::string> columns);
  // Continues the file at `path` (a resumed run): its header must be these columns and it must
  // hold at least keep_rows rows; rows after the first keep_rows are dropped (the file is
  // rewritten atomically first) and new rows are appended. kept_times() gives the first column
  // of the rows kept. Throws std::runtime_error naming the file and the fix.
  GaugeWriter(const std::string& path, std::vector<std::string> columns, std::size_t keep_rows);
  ~GaugeWriter();
  GaugeWriter(const GaugeWriter&) = delete;
  GaugeWriter& operator=(const GaugeWriter&) = delete;
  GaugeWriter(GaugeWriter&& o) noexcept;
  GaugeWriter& operator=(GaugeWriter&& o) noexcept;

  // One value per column (else std::invalid_argument). Integral values below 1e15 print as
  // integers, others with "%.9g". Throws WriteError when the line cannot be written.
  void row(const std::vector<double>& values);

  const std::string& path() const { return path_; }
  const std::vector<std::string>& columns() const { return columns_; }
  const std::vector<double>& kept_times() const { return kept_times_; }

 private:
  void put(const std::string& line);

  std::string path_;
  std::vector<std::string> columns_;
  std::vector<double> kept_times_;
  std::FILE* file_ = nullptr;
  long complete_ = 0;  // bytes of whole lines in the file
};

// The text one value takes in a gauge file.
std::string format_gauge_value(double v);

}  // namespace sphfem::io
