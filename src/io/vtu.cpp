#include "sphfem/io/vtu.h"

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <sstream>
#include <stdexcept>

#include "sphfem/io/atomic_file.h"
#include "sphfem/io/endian.h"
#include "sphfem/io/xml.h"

namespace sphfem::io {
namespace {

// One array of the appended section: its XML description and how to write its bytes.
struct Block {
  std::string xml_head;  // `<DataArray type=... Name=... NumberOfComponents=...`
  std::uint64_t bytes;
  std::function<void(AtomicFile&)> write;
};

template <class T>
Block make_block(const char* type, const std::string& name, int components,
                 const std::vector<T>& v) {
  std::ostringstream head;
  head << "<DataArray type=\"" << type << "\" Name=\"" << xml_escape(name)
       << "\" NumberOfComponents=\"" << components << "\"";
  return {head.str(), static_cast<std::uint64_t>(v.size() * sizeof(T)),
          [&v](AtomicFile& f) { f.write_le(v); }};
}

Block array_block(const DataArray& a) {
  if (a.is_int()) return make_block("Int32", a.name, a.components, a.ivalues);
  return make_block("Float32", a.name, a.components, a.values);
}

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open '" + path + "'");
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

void write_vtu(const std::string& path, const PointSet& frame) {
  validate(frame);
  const std::size_t n = frame.size();

  // A cloud gets one vertex cell per point: ParaView draws no points without cells.
  std::vector<std::int32_t> vertex_conn, vertex_offsets;
  std::vector<std::uint8_t> vertex_types;
  const bool cloud = frame.types.empty();
  if (cloud) {
    vertex_conn.resize(n);
    vertex_offsets.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      vertex_conn[i] = static_cast<std::int32_t>(i);
      vertex_offsets[i] = static_cast<std::int32_t>(i + 1);
    }
    vertex_types.assign(n, kVtkVertex);
  }
  const auto& conn = cloud ? vertex_conn : frame.connectivity;
  const auto& offsets = cloud ? vertex_offsets : frame.offsets;
  const auto& types = cloud ? vertex_types : frame.types;

  std::vector<Block> point_blocks, cell_blocks, cells;
  for (const auto& a : frame.point_data) point_blocks.push_back(array_block(a));
  for (const auto& a : frame.cell_data) cell_blocks.push_back(array_block(a));
  Block points = make_block("Float32", "Points", 3, frame.positions);
  cells.push_back(make_block("Int32", "connectivity", 1, conn));
  cells.push_back(make_block("Int32", "offsets", 1, offsets));
  cells.push_back(make_block("UInt8", "types", 1, types));

  // Appended blocks follow the order of the XML; each is a UInt64 byte count and the bytes.
  std::uint64_t offset = 0;
  std::vector<const Block*> order;
  std::ostringstream xml;
  auto add = [&](const Block& b, const char* indent) {
    xml << indent << b.xml_head << " format=\"appended\" offset=\"" << offset << "\"/>\n";
    offset += sizeof(std::uint64_t) + b.bytes;
    order.push_back(&b);
  };
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\""
      << " header_type=\"UInt64\">\n"
      << "  <UnstructuredGrid>\n"
      << "    <Piece NumberOfPoints=\"" << n << "\" NumberOfCells=\"" << types.size() << "\">\n"
      << "      <PointData>\n";
  for (const auto& b : point_blocks) add(b, "        ");
  xml << "      </PointData>\n"
      << "      <CellData>\n";
  for (const auto& b : cell_blocks) add(b, "        ");
  xml << "      </CellData>\n"
      << "      <Points>\n";
  add(points, "        ");
  xml << "      </Points>\n"
      << "      <Cells>\n";
  for (const auto& b : cells) add(b, "        ");
  xml << "      </Cells>\n"
      << "    </Piece>\n"
      << "  </UnstructuredGrid>\n"
      << "  <AppendedData encoding=\"raw\">\n"
      << "   _";

  write_file_atomic(path, [&](AtomicFile& f) {
    f.write(xml.str());
    for (const Block* b : order) {
      f.write_le(&b->bytes, 1);
      b->write(f);
    }
    f.write("\n  </AppendedData>\n</VTKFile>\n");
  });
}

namespace {

// One array of the <Cells> section: Int32 connectivity and offsets, UInt8 types.
template <class Bad>
void read_cell_block(std::map<std::string, std::string>& attrs, const char* src,
                     std::uint64_t bytes, std::size_t n_cells, PointSet& out, const Bad& bad) {
  const std::string& name = attrs["Name"];
  if (name == "types") {
    if (attrs["type"] != "UInt8" || bytes != n_cells)
      throw bad("cell types are not UInt8 per cell");
    out.types.assign(src, src + bytes);
    return;
  }
  if (name != "connectivity" && name != "offsets") return;
  if (attrs["type"] != "Int32" || bytes % 4 != 0) throw bad("cell " + name + " are not Int32");
  if (name == "offsets" && bytes != 4 * n_cells) throw bad("one offset per cell expected");
  std::vector<std::int32_t>& v = name == "offsets" ? out.offsets : out.connectivity;
  v.resize(bytes / 4);
  copy_le(v.data(), src, v.size(), 4);
}

// Both readers: points and point arrays always; with `cells`, also connectivity, offsets,
// types and the cell arrays.
PointSet read_vtu_file(const std::string& path, bool cells) {
  const std::string data = read_all(path);
  // Parts of the message come from the file: bytes that are not printable text are shown as
  // '?', so the message stays one line whatever the file holds (found by fuzzing).
  auto bad = [&](std::string why) {
    for (char& c : why)
      if (static_cast<unsigned char>(c) < 32 || c == 127) c = '?';
    return std::runtime_error("'" + path + "' is not a VTU file written by write_vtu: " + why);
  };
  // Numbers in attributes go through std::sto*; report their failures as a bad file.
  auto number = [&](const std::string& text) -> std::uint64_t {
    std::size_t used = 0;
    unsigned long long v = 0;
    try {
      v = std::stoull(text, &used);
    } catch (const std::exception&) { used = 0; }
    if (text.empty() || used != text.size() || text[0] == '-')
      throw bad("'" + text + "' is not a count");
    return v;
  };
  const std::size_t appended = data.find("<AppendedData");
  if (appended == std::string::npos) throw bad("no appended data");
  const std::size_t underscore = data.find('_', data.find('>', appended));
  if (underscore == std::string::npos) throw bad("appended data has no start marker");
  const std::size_t base = underscore + 1;
  const std::size_t limit = data.rfind("</AppendedData>");
  if (limit == std::string::npos || limit < base) throw bad("appended data is not closed");
  // Only the text before the binary section is XML that can be scanned safely.
  const std::string xml = data.substr(0, appended);

  PointSet out;
  std::size_t n = 0, n_cells = 0;
  bool have_piece = false, have_points = false;
  std::string section;
  for (std::size_t lt = xml.find('<'); lt != std::string::npos; lt = xml.find('<', lt + 1)) {
    const std::size_t gt = xml.find('>', lt);
    if (gt == std::string::npos) throw bad("unterminated tag");
    std::string tag = xml.substr(lt + 1, gt - lt - 1);
    if (tag.empty() || tag[0] == '?' || tag[0] == '!') continue;
    if (tag[0] == '/') {
      if (tag.substr(1) == section) section.clear();
      continue;
    }
    const bool self_closing = tag.back() == '/';
    const std::string name = tag.substr(0, tag.find_first_of(" \t\r\n/"));
    auto attrs = xml_attributes(tag);
    if (name == "VTKFile") {
      if (attrs["type"] != "UnstructuredGrid") throw bad("not an UnstructuredGrid");
      if (attrs["byte_order"] != "LittleEndian") throw bad("not little endian");
      if (attrs["header_type"] != "UInt64") throw bad("block headers are not UInt64");
    } else if (name == "Piece") {
      if (have_piece) throw bad("more than one piece");
      have_piece = true;
      n = number(attrs["NumberOfPoints"]);
      if (n > data.size()) throw bad("more points than bytes");
      n_cells = attrs.count("NumberOfCells") ? number(attrs["NumberOfCells"]) : 0;
      if (n_cells > data.size()) throw bad("more cells than bytes");
    } else if (name == "PointData" || name == "CellData" || name == "Points" || name == "Cells") {
      if (!self_closing) section = name;
    } else if (name == "DataArray") {
      // Every block must lie inside the appended section, so a cut file is caught even
      // where the cut spares the points.
      const std::uint64_t offset = number(attrs["offset"]);
      std::uint64_t bytes = 0;
      if (attrs["format"] != "appended") throw bad("array '" + attrs["Name"] + "' not appended");
      if (offset > limit || base + offset + sizeof(bytes) > limit)
        throw bad("array '" + attrs["Name"] + "' truncated");
      const std::size_t at = base + offset;
      copy_le(&bytes, data.data() + at, 1, sizeof(bytes));
      if (bytes > limit - at - sizeof(bytes)) throw bad("array '" + attrs["Name"] + "' truncated");
      if (section == "Cells" && cells) {
        read_cell_block(attrs, data.data() + at + sizeof(bytes), bytes, n_cells, out, bad);
        continue;
      }
      const bool cell_data = section == "CellData" && cells;
      if (section != "PointData" && section != "Points" && !cell_data) continue;

      const std::string& type = attrs["type"];
      if (type != "Float32" && type != "Int32") throw bad("unsupported type '" + type + "'");
      const std::uint64_t components =
          attrs.count("NumberOfComponents") ? number(attrs["NumberOfComponents"]) : 1;
      if (components < 1 || components > 64) throw bad("bad component count");
      const std::size_t count = (cell_data ? n_cells : n) * components;
      if (bytes != count * 4) throw bad("array '" + attrs["Name"] + "' has the wrong size");
      const char* src = data.data() + at + sizeof(bytes);

      if (section == "Points") {
        if (components != 3) throw bad("points without 3 components");
        out.positions.resize(count);
        copy_le(out.positions.data(), src, count, 4);
        have_points = true;
      } else {
        DataArray a;
        a.name = attrs["Name"];
        a.components = static_cast<int>(components);
        if (type == "Int32") {
          a.ivalues.resize(count);
          copy_le(a.ivalues.data(), src, count, 4);
        } else {
          a.values.resize(count);
          copy_le(a.values.data(), src, count, 4);
        }
        (cell_data ? out.cell_data : out.point_data).push_back(std::move(a));
      }
    }
  }
  if (!have_piece) throw bad("no piece");
  if (!have_points) throw bad("no points");
  if (cells) {
    // A point cloud reads back as written: one vertex cell per point, kept as no cells.
    const bool cloud = std::all_of(out.types.begin(), out.types.end(),
                                   [](std::uint8_t t) { return t == kVtkVertex; });
    if (cloud) {
      out.connectivity.clear();
      out.offsets.clear();
      out.types.clear();
      out.cell_data.clear();
    }
    try {
      validate(out);
    } catch (const std::invalid_argument& e) { throw bad(e.what()); }
  }
  return out;
}

}  // namespace

PointSet read_vtu_points(const std::string& path) { return read_vtu_file(path, false); }

PointSet read_vtu(const std::string& path) { return read_vtu_file(path, true); }

}  // namespace sphfem::io
