// Surface import through Assimp, and the small helpers that place a surface in the scene.
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <array>
#include <assimp/Importer.hpp>
#include <cstring>
#include <fstream>
#include <map>

#include "sphfem/fem/import.h"

namespace sphfem {

namespace {

constexpr const char* kExportHint =
    "export it as OBJ, PLY or STL (ASCII or binary), e.g. in MeshLab: File > Export Mesh As";

// Exact position key; + 0.0 folds -0 into +0 so the two compare equal.
std::array<double, 3> key_of(const aiVector3D& p) {
  return {double(p.x) + 0.0, double(p.y) + 0.0, double(p.z) + 0.0};
}

}  // namespace

SurfaceMesh load_surface(const std::string& path) {
  if (!std::ifstream(path).good())
    throw MeshError(path, "cannot open the file", "check the path and that the file is readable");

  Assimp::Importer importer;
  // Per-face normals (STL), texture seams and colours split vertices; dropping them first lets
  // JoinIdenticalVertices merge by position alone.
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                              aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                  aiComponent_COLORS | aiComponent_TEXCOORDS |
                                  aiComponent_BONEWEIGHTS);
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_RemoveComponent | aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (!scene) {
    std::string why = importer.GetErrorString();
    std::replace(why.begin(), why.end(), '\n', ' ');
    throw MeshError(path, "cannot read it as a surface mesh (" + why + ")", kExportHint);
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
