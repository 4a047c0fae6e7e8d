#include "sphfem/io/frame.h"

#include <limits>
#include <stdexcept>

namespace sphfem::io {
namespace {

void check_array(const DataArray& a, std::size_t n, const char* kind) {
  if (a.name.empty()) throw std::invalid_argument(std::string(kind) + " array without a name");
  if (a.components < 1)
    throw std::invalid_argument(std::string(kind) + " array '" + a.name +
                                "' has fewer than one component");
  if (!a.values.empty() && !a.ivalues.empty())
    throw std::invalid_argument(std::string(kind) + " array '" + a.name +
                                "' has both float and int values");
  std::size_t want = n * static_cast<std::size_t>(a.components);
  if (a.size() != want)
    throw std::invalid_argument(std::string(kind) + " array '" + a.name + "' has " +
                                std::to_string(a.size()) + " values, expected " +
                                std::to_string(want));
}

}  // namespace

void validate(const PointSet& f) {
  if (f.positions.size() % 3 != 0)
    throw std::invalid_argument("positions size " + std::to_string(f.positions.size()) +
                                " is not a multiple of 3");
  const std::size_t n = f.size();
  // Indices and offsets are written as Int32.
  if (n > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw std::invalid_argument("too many points for 32-bit indices");
  for (const auto& a : f.point_data) check_array(a, n, "point");

  if (f.offsets.size() != f.types.size())
    throw std::invalid_argument("cell offsets (" + std::to_string(f.offsets.size()) +
                                ") and types (" + std::to_string(f.types.size()) +
                                ") differ in length");
  if (f.types.empty() && !f.connectivity.empty())
    throw std::invalid_argument("connectivity given without cell types/offsets");
  std::int32_t prev = 0;
  for (std::size_t i = 0; i < f.offsets.size(); ++i) {
    if (f.offsets[i] < prev)
      throw std::invalid_argument("cell offsets decrease at cell " + std::to_string(i));
    prev = f.offsets[i];
  }
  if (!f.offsets.empty() && static_cast<std::size_t>(prev) != f.connectivity.size())
    throw std::invalid_argument("last cell offset " + std::to_string(prev) +
                                " does not match connectivity size " +
                                std::to_string(f.connectivity.size()));
  for (std::size_t i = 0; i < f.connectivity.size(); ++i) {
    std::int32_t c = f.connectivity[i];
    if (c < 0 || static_cast<std::size_t>(c) >= n)
      throw std::invalid_argument("connectivity[" + std::to_string(i) + "] = " + std::to_string(c) +
                                  " is not a point index");
  }
  for (const auto& a : f.cell_data) check_array(a, f.num_cells(), "cell");
}

}  // namespace sphfem::io
