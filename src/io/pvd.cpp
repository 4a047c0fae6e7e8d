#include "sphfem/io/pvd.h"

#include <charconv>
#include <cmath>
#include <stdexcept>

#include "sphfem/io/atomic_file.h"
#include "sphfem/io/xml.h"

namespace sphfem::io {
namespace {

// Shortest text that reads back as the same double, so close times stay distinct.
std::string format_time(double t) {
  char buf[32];
  auto res = std::to_chars(buf, buf + sizeof(buf), t);
  return std::string(buf, res.ptr);
}

}  // namespace

PvdCollection::PvdCollection(std::string path) : path_(std::move(path)) {}

void PvdCollection::add(double time, const std::string& file, int part) {
  if (!std::isfinite(time))
    throw std::invalid_argument("frame '" + file + "' has a non-finite time");
  entries_.push_back({time, file, part});

  std::string text =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  for (const auto& e : entries_)
    text += "    <DataSet timestep=\"" + format_time(e.time) + "\" group=\"\" part=\"" +
            std::to_string(e.part) + "\" file=\"" + xml_escape(e.file) + "\"/>\n";
  text += "  </Collection>\n</VTKFile>\n";
  try {
    write_file_atomic(path_, text);
  } catch (...) {
    // Keep the list in step with the file on disk so a retry does not duplicate the frame.
    entries_.pop_back();
    throw;
  }
}

}  // namespace sphfem::io
