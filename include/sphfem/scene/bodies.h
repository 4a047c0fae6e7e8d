// The deformable bodies of a scene: rest meshes from the shapes and files it names, their
// checks, and the compiled model the FEM solver runs.
// SceneSpec::bodies -> rest mesh + pinned flags (build_body_mesh) -> BodiesModel (fem/model.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sphfem/fem/mesh.h"
#include "sphfem/fem/model.h"
#include "sphfem/scene/spec.h"

namespace sphfem {

struct BodyMesh {
  TetMesh mesh;                      // rest positions in the scene, m
  std::vector<std::uint8_t> pinned;  // per node: 1 = held fixed
};

// Nodes and tetrahedra a generated shape will have, counted without building it (upper bounds
// for the cup, whose hollow is cut from a full lattice); zero for a mesh file.
struct ShapeSize {
  double nodes = 0, tets = 0;
};
ShapeSize shape_size(const BodySpec& body);

// The rest mesh a body's shape or file gives, before any check of its place in the scene.
// `scene_file` names the scene in messages and is the folder a relative mesh path starts
// from. Throws SceneError (a mesh file missing, unreadable or unfit; a shape too fine).
TetMesh body_rest_mesh(const BodySpec& body, const std::string& at, const std::string& scene_file);

// The rest mesh and pinned flags of scene.bodies[index], checked against the scene. Throws
// SceneError naming the file, the JSON path and the fix: everything body_rest_mesh throws,
// the body reaching outside the domain, a pinned box holding no node, a pinned index out of
// range.
BodyMesh build_body_mesh(const SceneSpec& scene, std::size_t index, const std::string& scene_file);

// Checks of scene.bodies for validate_scene: names and shape parameters, then everything
// build_body_mesh checks. Meshes are built (and a surface tetrahedralised) to do so.
void check_bodies(const SceneSpec& scene, const std::string& scene_file);

// Every body of the scene compiled for the solver: the scene's fem settings and gravity, and
// the tank as the walls the nodes may not leave. Throws SceneError like build_body_mesh.
BodiesModel compile_scene_bodies(const SceneSpec& scene);

// Global index (BodiesModel order) of the rest node of body `body` nearest to `p`.
int nearest_rest_node(const BodiesModel& model, int body, const Vec3d& p);

// Index of the body called `name` in scene.bodies, or -1.
int body_index(const SceneSpec& scene, const std::string& name);

}  // namespace sphfem
