// Line and field reading shared by the text tetrahedral-mesh readers (TetGen, Gmsh).
#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "sphfem/fem/import.h"

namespace sphfem::import_detail {

namespace {
constexpr const char* kReexport = "fix the line or re-export the mesh";
}

TextLines::TextLines(const std::string& path) : path_(path) {
  std::ifstream in(path);
  if (!in) throw MeshError(path, "cannot open the file", "check the path and that it is readable");
  for (std::string l; std::getline(in, l);) lines_.push_back(std::move(l));
}

bool TextLines::next() {
  while (line_ < lines_.size()) {
    std::string l = lines_[line_++];
    const std::size_t hash = l.find('#');
    if (hash != std::string::npos) l.resize(hash);
    std::istringstream words(l);
    fields_.clear();
    for (std::string w; words >> w;) fields_.push_back(w);
    if (!fields_.empty()) return true;
  }
  fields_.clear();
  return false;
}

void TextLines::need(std::size_t count, const char* what) const {
  if (fields_.size() < count)
    fail("expected " + std::to_string(count) + " fields (" + what + "), found " +
             std::to_string(fields_.size()),
         kReexport);
}

long TextLines::integer(std::size_t i, const char* what) const {
  need(i + 1, what);
  const std::string& f = fields_[i];
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(f.c_str(), &end, 10);
  if (end == f.c_str() || *end != '\0' || errno != 0)
    fail("expected an integer (" + std::string(what) + "), found '" + f + "'", kReexport);
  return v;
}

double TextLines::real(std::size_t i, const char* what) const {
  need(i + 1, what);
  const std::string& f = fields_[i];
  char* end = nullptr;
  const double v = std::strtod(f.c_str(), &end);
  if (end == f.c_str() || *end != '\0')
    fail("expected a number (" + std::string(what) + "), found '" + f + "'", kReexport);
  return v;
}

void TextLines::fail(const std::string& what, const std::string& fix) const {
  throw MeshError(path_, "line " + std::to_string(line_) + ": " + what, fix);
}

void TextLines::fail_eof(const char* expected) const {
  throw MeshError(path_, std::string("the file ends before ") + expected,
                  "the file is cut short; export it again");
}

}  // namespace sphfem::import_detail
