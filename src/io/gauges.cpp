#include "sphfem/io/gauges.h"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <utility>

#include "sphfem/io/atomic_file.h"

namespace sphfem::io {
namespace {

// RFC 4180 quoting, needed only when a column name holds a separator or a quote.
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

}  // namespace

std::string format_gauge_value(double v) {
  char buf[64];
  if (std::isfinite(v) && std::fabs(v) < 1e15 && v == std::trunc(v))
    std::snprintf(buf, sizeof(buf), "%.0f", v);
  else
    std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

GaugeWriter::GaugeWriter(const std::string& path, std::vector<std::string> columns)
    : path_(path), columns_(std::move(columns)) {
  if (columns_.empty()) throw std::invalid_argument("gauge file '" + path_ + "' has no columns");
  file_ = std::fopen(path_.c_str(), "w");
  if (!file_) {
    const int err = errno;
    std::string msg = "cannot open gauge file '" + path_ + "': " + std::strerror(err);
    const std::filesystem::path parent = std::filesystem::path(path_).parent_path();
    std::error_code ec;
    if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
      msg += " (folder '" + parent.string() + "' does not exist)";
    throw WriteError(msg);
  }
  // Unbuffered: a failed line must not linger in a buffer that a later flush would write.
  std::setvbuf(file_, nullptr, _IONBF, 0);
  std::string header;
  for (std::size_t i = 0; i < columns_.size(); ++i)
    header += (i ? "," : "") + csv_field(columns_[i]);
  try {
    put(header + "\n");
  } catch (...) {
    std::fclose(file_);  // the destructor does not run for a throwing constructor
    throw;
  }
}

GaugeWriter::GaugeWriter(const std::string& path, std::vector<std::string> columns,
                         std::size_t keep_rows)
    : path_(path), columns_(std::move(columns)) {
  std::ifstream in(path_);
  const std::string fix = "; run again without --resume";
  if (!in)
    throw std::runtime_error("cannot resume gauge file '" + path_ + "': it is missing" + fix);
  std::string header, line, kept;
  std::getline(in, header);
  std::string expected;
  for (std::size_t i = 0; i < columns_.size(); ++i)
    expected += (i ? "," : "") + csv_field(columns_[i]);
  if (header != expected)
    throw std::runtime_error("cannot resume gauge file '" + path_ +
                             "': its columns are not this scene's" + fix);
  kept = header + "\n";
  while (kept_times_.size() < keep_rows && std::getline(in, line)) {
    if (line.empty()) break;
    kept += line + "\n";
    kept_times_.push_back(std::strtod(line.c_str(), nullptr));
  }
  if (kept_times_.size() < keep_rows)
    throw std::runtime_error("cannot resume gauge file '" + path_ + "': it has " +
                             std::to_string(kept_times_.size()) + " rows, the checkpoint follows " +
                             std::to_string(keep_rows) + fix);
  in.close();
  write_file_atomic(path_, kept);
  file_ = std::fopen(path_.c_str(), "a");
  if (!file_) throw WriteError("cannot open gauge file '" + path_ + "': " + std::strerror(errno));
  std::setvbuf(file_, nullptr, _IONBF, 0);
  complete_ = long(kept.size());
}

GaugeWriter::~GaugeWriter() {
  if (file_) std::fclose(file_);
}

GaugeWriter::GaugeWriter(GaugeWriter&& o) noexcept
    : path_(std::move(o.path_)),
      columns_(std::move(o.columns_)),
      kept_times_(std::move(o.kept_times_)),
      file_(o.file_),
      complete_(o.complete_) {
  o.file_ = nullptr;
}

GaugeWriter& GaugeWriter::operator=(GaugeWriter&& o) noexcept {
  if (this != &o) {
    if (file_) std::fclose(file_);
    path_ = std::move(o.path_);
    columns_ = std::move(o.columns_);
    kept_times_ = std::move(o.kept_times_);
    file_ = o.file_;
    complete_ = o.complete_;
    o.file_ = nullptr;
  }
  return *this;
}

void GaugeWriter::row(const std::vector<double>& values) {
  if (values.size() != columns_.size())
    throw std::invalid_argument("gauge row for '" + path_ + "' has " +
                                std::to_string(values.size()) + " values, expected " +
                                std::to_string(columns_.size()));
  std::string line;
  for (std::size_t i = 0; i < values.size(); ++i)
    line += (i ? "," : "") + format_gauge_value(values[i]);
  put(line + "\n");
}

void GaugeWriter::put(const std::string& line) {
  if (!file_) throw std::logic_error("gauge file '" + path_ + "' is closed");
  errno = 0;
  // Writing every line at once costs little at gauge rates and keeps rows written before a crash.
  if (std::fwrite(line.data(), 1, line.size(), file_) != line.size() || std::fflush(file_) != 0) {
    const int err = errno ? errno : EIO;
    // Cut off the part of the line that was written; the rows before it stay whole.
    std::clearerr(file_);
    if (ftruncate(fileno(file_), complete_) != 0) {
      // Nothing more can be done about the file; the message below says why it stopped.
    }
    throw WriteError("cannot write gauge file '" + path_ + "': " + std::strerror(err));
  }
  complete_ += long(line.size());
}

}  // namespace sphfem::io
