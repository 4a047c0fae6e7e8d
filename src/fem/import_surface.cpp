// Surface import through Assimp, and the small helpers that place a surface in the scene.
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <array>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <vector>

#include "sphfem/fem/import.h"

namespace sphfem {

namespace {

constexpr const char* kExportHint =
    "export it as OBJ, PLY or STL (ASCII or binary), e.g. in MeshLab: File > Export Mesh As";

// Exact position key; + 0.0 folds -0 into +0 so the two compare equal.
std::array<double, 3> key_of(const aiVector3D& p) {
  return {double(p.x) + 0.0, double(p.y) + 0.0, double(p.z) + 0.0};
}

// The bytes a PLY property takes at least: its type's size in a binary file (a list, its count's
// size), a value and a separator in an ASCII one; 0 for a type Assimp does not know.
std::size_t ply_type_size(const std::string& type) {
  static const std::map<std::string, std::size_t> sizes = {
      {"char", 1},   {"int8", 1},    {"uchar", 1},  {"uint8", 1},  {"short", 2}, {"int16", 2},
      {"ushort", 2}, {"uint16", 2},  {"int", 4},    {"int32", 4},  {"uint", 4},  {"uint32", 4},
      {"float", 4},  {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto it = sizes.find(type);
  return it == sizes.end() ? 0 : it->second;
}

// Checks a PLY header against the file before Assimp reads it (`end` is where end_header is):
// - every line is a header line (Assimp loops forever over one it does not know);
// - no element is declared twice (Assimp wrote past its array);
// - every element count is a number whose elements fit in the bytes after the header (Assimp
//   allocates for the count it is given: "element face 4294967295" asked for 64 GiB);
// - in an ASCII body, each list's count fits on its line (Assimp takes a count of 2^31 as given
//   and spends minutes on it).
// All four were found by fuzzing.
void check_ply_header(const std::string& path, const std::string& data, std::size_t end) {
  struct Element {
    std::string name, count_text;
    double count = 0;
    std::vector<bool> list;   // per property
    double binary_bytes = 0;  // at least, per element
  };
  std::vector<Element> elements;
  bool ascii = false;
  std::istringstream header(data.substr(0, end));
  for (std::string line; std::getline(header, line);) {
    std::istringstream words(line);
    std::string key, word;
    words >> key >> word;
    if (key == "format") ascii = word == "ascii";
    if (key == "element") {
      // Assimp sizes an element's array by its first declaration and fills it from every one:
      // "element vertex 4" then "element vertex 8" wrote past the end of the heap block.
      for (const Element& e : elements)
        if (e.name == word)
          throw MeshError(path, "the PLY header declares the element '" + word + "' twice",
                          kExportHint);
      elements.push_back({});
      elements.back().name = word;
      words >> elements.back().count_text;
    }
    if (key == "property" && !elements.empty()) {
      Element& e = elements.back();
      e.list.push_back(word == "list");
      if (word == "list") words >> word;  // a list takes its count's bytes at least
      e.binary_bytes += double(ply_type_size(word));
    }
    static const char* const known[] = {"ply",     "format",   "comment", "obj_info",
                                        "element", "property", ""};
    if (std::find(std::begin(known), std::end(known), key) == std::end(known))
      throw MeshError(path, "the PLY header has a line that is not a header line ('" + key + "')",
                      kExportHint);
  }

  const std::size_t body_at = data.find('\n', end);
  const double body = body_at == std::string::npos ? 0.0 : double(data.size() - body_at - 1);
  double needed = 0;  // bytes the elements take at least
  for (Element& e : elements) {
    const std::string& c = e.count_text;
    if (c.empty() || c.size() > 20 || c.find_first_not_of("0123456789") != std::string::npos)
      throw MeshError(path,
                      "the PLY header's element '" + e.name + "' has no count ('" + c +
                          "' is not a whole number)",
                      kExportHint);
    e.count = std::strtod(c.c_str(), nullptr);
    // ASCII: a value and a space or a line break per property (the last line may lack its
    // break); either way at least one byte per element.
    const double each = std::max(1.0, ascii ? 2.0 * double(e.list.size()) : e.binary_bytes);
    needed += e.count * each;
    if (needed > body + 1)
      throw MeshError(path,
                      "the PLY header announces " + c + " '" + e.name +
                          "' elements, more than the " + std::to_string(std::size_t(body)) +
                          " bytes after the header can hold (is the file cut short?)",
                      kExportHint);
  }
  if (!ascii || body_at == std::string::npos) return;

  std::istringstream lines(data.substr(body_at + 1));
  for (const Element& e : elements)
    for (double i = 0; i < e.count; ++i) {
      std::string line;
      do {
        if (!std::getline(lines, line)) return;  // a file cut short Assimp reports itself
      } while (line.find_first_not_of(" \t\r") == std::string::npos);
      std::istringstream words(line);
      std::vector<std::string> tokens;
      for (std::string t; words >> t;) tokens.push_back(t);
      std::size_t at = 0;
      for (bool list : e.list) {
        if (at >= tokens.size()) break;
        if (!list) {
          ++at;
          continue;
        }
        const double n = std::strtod(tokens[at].c_str(), nullptr);
        const double room = double(tokens.size() - at - 1);
        if (!(n >= 0 && n <= room))
          throw MeshError(path,
                          "a list in the PLY body announces " + tokens[at] +
                              " values on a line that holds " + std::to_string(tokens.size()),
                          kExportHint);
        at += 1 + std::size_t(n);
      }
    }
}

// Where the PLY header's end_header line starts, or npos. It must be a line of its own: Assimp
// loops forever over a header whose only "end_header" ends a comment (found by fuzzing).
std::size_t find_end_header(const std::string& data) {
  for (std::size_t at = 0; at < data.size();) {
    const std::size_t nl = std::min(data.find('\n', at), data.size());
    std::string line = data.substr(at, nl - at);
    line.erase(0, std::min(line.size(), line.find_first_not_of(" \t")));
    line.erase(line.find_last_not_of(" \t\r") + 1);  // npos + 1 == 0: all blank
    if (line == "end_header") return at;
    at = nl + 1;
  }
  return std::string::npos;
}

// Assimp's text readers can loop forever over a damaged text file (found by fuzzing: a PLY
// header with NUL bytes and no end_header line never returns), so the text parts are checked
// first: a PLY header must be text ending in end_header, an OBJ or ASCII STL file text.
void check_text_parts(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  auto is_text = [](unsigned char c) { return c == '\n' || c == '\r' || c == '\t' || c >= 32; };
  if (ext == ".ply") {
    const std::size_t end = find_end_header(data);
    if (data.compare(0, 3, "ply") != 0 || end == std::string::npos)
      throw MeshError(path, "the PLY header is damaged (no \"ply\" first or no end_header line)",
                      kExportHint);
    if (!std::all_of(data.begin(), data.begin() + long(end), is_text))
      throw MeshError(path, "the PLY header holds bytes that are not text", kExportHint);
    check_ply_header(path, data, end);
    return;
  }
  // A binary STL is 84 bytes and 50 per triangle, whatever its first bytes say.
  std::uint32_t triangles = 0;
  if (data.size() >= 84) std::memcpy(&triangles, data.data() + 80, 4);
  const bool binary_stl = data.size() >= 84 && data.size() == 84 + 50 * std::uint64_t(triangles);
  if ((ext == ".obj" || (ext == ".stl" && !binary_stl)) && data.find('\0') != std::string::npos)
    throw MeshError(path, "the file holds NUL bytes, so it is neither a text file nor a binary STL",
                    kExportHint);
}

}  // namespace

SurfaceMesh load_surface(const std::string& path) {
  if (!std::ifstream(path).good())
    throw MeshError(path, "cannot open the file", "check the path and that the file is readable");
  check_text_parts(path);

  Assimp::Importer importer;
  // Per-face normals (STL), texture seams and colours split vertices; dropping them first lets
  // JoinIdenticalVertices merge by position alone.
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                              aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                  aiComponent_COLORS | aiComponent_TEXCOORDS |
                                  aiComponent_BONEWEIGHTS);
  // Read and validated alone first: a corrupt file (a face indexing past the vertices, a face
  // without corners, a coordinate that is not a number) is refused here, before the
  // post-processing steps, which read such faces out of bounds or stop on an assertion.
  const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
  auto refuse = [&](const std::string& why) {
    throw MeshError(path, "cannot read it as a surface mesh (" + why + ")", kExportHint);
  };
  if (!scene) {
    std::string why = importer.GetErrorString();
    std::replace(why.begin(), why.end(), '\n', ' ');
    refuse(why);
  }
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    for (unsigned f = 0; f < mesh->mNumFaces; ++f)
      if (mesh->mFaces[f].mNumIndices == 0) refuse("face " + std::to_string(f) + " has no corners");
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        refuse("vertex " + std::to_string(v) + " has a coordinate that is not a finite number");
    }
  }
  scene = importer.ApplyPostProcessing(aiProcess_RemoveComponent | aiProcess_Triangulate |
                                       aiProcess_JoinIdenticalVertices |
                                       aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (!scene) {
    std::string why = importer.GetErrorString();
    std::replace(why.begin(), why.end(), '\n', ' ');
    refuse(why);
  }

  // Meshes of one file (OBJ groups, materials) share positions that Assimp keeps apart, so
  // vertices are merged again across meshes.
  SurfaceMesh s;
  s.source = path;
  std::map<std::array<double, 3>, int> index;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    std::vector<int> id(mesh->mNumVertices);
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const auto k = key_of(mesh->mVertices[v]);
      auto [it, added] = index.emplace(k, int(s.x.size()));
      if (added) s.x.push_back(Vec3d(k[0], k[1], k[2]));
      id[v] = it->second;
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines carry no surface
      const Tri t{{id[face.mIndices[0]], id[face.mIndices[1]], id[face.mIndices[2]]}};
      // A face that merging collapsed to a point or a segment has no area and no edges of
      // its own to contribute: dropping it leaves the surface as it was.
      if (t.v[0] == t.v[1] || t.v[1] == t.v[2] || t.v[2] == t.v[0]) continue;
      s.tris.push_back(t);
    }
  }
  if (s.tris.empty())
    throw MeshError(path, "the file contains no triangles or polygons",
                    "export the body's surface, not only points or lines");

  // Keep only vertices that triangles use (merging and dropping faces can orphan some).
  std::vector<int> remap(s.x.size(), -1);
  std::vector<Vec3d> used;
  for (Tri& t : s.tris)
    for (int& v : t.v) {
      if (remap[v] < 0) {
        remap[v] = int(used.size());
        used.push_back(s.x[v]);
      }
      v = remap[v];
    }
  s.x = std::move(used);
  return s;
}

void transform(SurfaceMesh& s, double scale, const Vec3d& offset) {
  for (Vec3d& p : s.x) p = p * scale + offset;
}

std::pair<Vec3d, Vec3d> bounds(const std::vector<Vec3d>& x) {
  if (x.empty()) return {Vec3d(), Vec3d()};
  Vec3d lo = x[0], hi = x[0];
  for (const Vec3d& p : x) {
    lo = vmin(lo, p);
    hi = vmax(hi, p);
  }
  return {lo, hi};
}

}  // namespace sphfem
