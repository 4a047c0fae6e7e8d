#include "sphfem/io/ply.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "sphfem/io/atomic_file.h"
#include "sphfem/io/endian.h"

namespace sphfem::io {
namespace {

// Property names of one array, one per component.
std::vector<std::string> property_names(const DataArray& a) {
  static const char* const kAxes[] = {"_x", "_y", "_z"};
  if (a.components == 1) return {a.name};
  std::vector<std::string> names;
  for (int c = 0; c < a.components; ++c)
    names.push_back(a.name + (a.components <= 3 ? std::string(kAxes[c]) : "_" + std::to_string(c)));
  return names;
}

bool all_triangles(const PointSet& f) {
  if (f.types.empty()) return false;
  for (std::size_t i = 0; i < f.types.size(); ++i) {
    const std::int32_t begin = i ? f.offsets[i - 1] : 0;
    if (f.types[i] != kVtkTriangle || f.offsets[i] - begin != 3) return false;
  }
  return true;
}

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open '" + path + "'");
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

void write_ply(const std::string& path, const PointSet& frame) {
  validate(frame);
  for (const auto& a : frame.point_data)
    for (char c : a.name)
      if (std::isspace(static_cast<unsigned char>(c)))
        throw std::invalid_argument("PLY property name '" + a.name + "' contains white space");
  const std::size_t n = frame.size();
  const bool faces = all_triangles(frame);

  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment sphfem frame\n"
         << "element vertex " << n << "\n"
         << "property float x\nproperty float y\nproperty float z\n";
  std::size_t row_bytes = 3 * sizeof(float);
  for (const auto& a : frame.point_data) {
    for (const auto& name : property_names(a))
      header << "property " << (a.is_int() ? "int " : "float ") << name << "\n";
    row_bytes += 4 * static_cast<std::size_t>(a.components);
  }
  if (faces)
    header << "element face " << frame.types.size() << "\n"
           << "property list uchar int vertex_indices\n";
  header << "end_header\n";

  write_file_atomic(path, [&](AtomicFile& f) {
    f.write(header.str());
    // PLY stores vertices row by row; interleave the arrays through a bounded buffer.
    const std::size_t rows_per_chunk = std::max<std::size_t>(1, (1 << 20) / row_bytes);
    std::vector<unsigned char> buf(rows_per_chunk * row_bytes);
    for (std::size_t first = 0; first < n; first += rows_per_chunk) {
      const std::size_t rows = std::min(rows_per_chunk, n - first);
      for (std::size_t r = 0; r < rows; ++r) {
        const std::size_t i = first + r;
        unsigned char* out = buf.data() + r * row_bytes;
        copy_le(out, &frame.positions[3 * i], 3, 4);
        out += 12;
        for (const auto& a : frame.point_data) {
          const std::size_t k = static_cast<std::size_t>(a.components);
          if (a.is_int())
            copy_le(out, &a.ivalues[k * i], k, 4);
          else
            copy_le(out, &a.values[k * i], k, 4);
          out += 4 * k;
        }
      }
      f.write(buf.data(), rows * row_bytes);
    }
    if (faces) {
      const std::uint8_t three = 3;
      for (std::size_t c = 0; c < frame.types.size(); ++c) {
        f.write(&three, 1);
        f.write_le(&frame.connectivity[3 * c], 3);
      }
    }
  });
}

PointSet read_ply_points(const std::string& path) {
  const std::string data = read_all(path);
  auto bad = [&](const std::string& why) {
    return std::runtime_error("'" + path + "' is not a PLY file written by write_ply: " + why);
  };
  const std::string end_marker = "end_header\n";
  const std::size_t end = data.find(end_marker);
  if (data.compare(0, 4, "ply\n") != 0 || end == std::string::npos) throw bad("no PLY header");
  const std::size_t body = end + end_marker.size();

  struct Property {
    std::string name;
    bool is_int;
  };
  std::vector<Property> props;
  std::size_t n = 0;
  bool in_vertex = false, have_vertex = false;
  std::istringstream header(data.substr(0, end));
  std::string line;
  while (std::getline(header, line)) {
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "format") {
      std::string format;
      words >> format;
      if (format != "binary_little_endian") throw bad("format '" + format + "'");
    } else if (key == "element") {
      std::string name;
      words >> name;
      if (have_vertex && name == "vertex") throw bad("two vertex elements");
      in_vertex = name == "vertex";
      if (in_vertex) {
        if (!(words >> n)) throw bad("vertex count missing");
        have_vertex = true;
      } else if (!have_vertex) {
        throw bad("elements before the vertices");
      }
    } else if (key == "property" && in_vertex) {
      std::string type, name;
      words >> type >> name;
      if (type != "float" && type != "int") throw bad("property type '" + type + "'");
      props.push_back({name, type == "int"});
    }
  }
  if (!have_vertex) throw bad("no vertex element");
  if (props.size() < 3 || props[0].name != "x" || props[1].name != "y" || props[2].name != "z" ||
      props[0].is_int || props[1].is_int || props[2].is_int)
    throw bad("vertices do not start with float x, y, z");
  const std::size_t row_bytes = 4 * props.size();
  if (n > (data.size() - body) / row_bytes) throw bad("vertex data truncated");

  // Regroup runs name_x,name_y[,name_z] and name_0,name_1,... into vector arrays.
  struct Group {
    DataArray array;
    std::size_t first;  // index of the first property
  };
  std::vector<Group> groups;
  auto base_of = [](const std::string& name, const std::string& suffix) {
    return name.size() > suffix.size() &&
                   name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0
               ? name.substr(0, name.size() - suffix.size())
               : std::string();
  };
  for (std::size_t p = 3; p < props.size();) {
    std::size_t len = 1;
    std::string base = base_of(props[p].name, "_x");
    std::vector<std::string> suffixes = {"_x", "_y", "_z"};
    if (base.empty()) {
      base = base_of(props[p].name, "_0");
      suffixes.clear();
    }
    if (!base.empty()) {
      for (std::size_t q = p + 1; q < props.size(); ++q) {
        const std::size_t k = q - p;
        const std::string want =
            base + (suffixes.empty() ? "_" + std::to_string(k) : (k < 3 ? suffixes[k] : "#"));
        if (props[q].name != want || props[q].is_int != props[p].is_int) break;
        len = k + 1;
      }
    }
    Group g;
    g.first = p;
    g.array.name = len > 1 ? base : props[p].name;
    g.array.components = static_cast<int>(len);
    groups.push_back(std::move(g));
    p += len;
  }

  PointSet out;
  out.positions.resize(3 * n);
  for (auto& g : groups) {
    const std::size_t count = n * static_cast<std::size_t>(g.array.components);
    if (props[g.first].is_int)
      g.array.ivalues.resize(count);
    else
      g.array.values.resize(count);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const char* row = data.data() + body + i * row_bytes;
    copy_le(&out.positions[3 * i], row, 3, 4);
    for (auto& g : groups) {
      const std::size_t k = static_cast<std::size_t>(g.array.components);
      const char* src = row + 4 * g.first;
      if (props[g.first].is_int)
        copy_le(&g.array.ivalues[k * i], src, k, 4);
      else
        copy_le(&g.array.values[k * i], src, k, 4);
    }
  }
  for (auto& g : groups) out.point_data.push_back(std::move(g.array));
  return out;
}

}  // namespace sphfem::io
