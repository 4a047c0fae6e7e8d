// Compiling rest meshes and materials into the flat model the solver uploads.
#include "sphfem/fem/model.h"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace sphfem {

namespace {

void check_material(const Material& m, const std::string& name) {
  auto bad = [&](const char* field, double v, const char* fix) {
    throw std::runtime_error("body '" + name + "': material." + field + " = " + std::to_string(v) +
                             "; " + fix);
  };
  if (!(m.density > 0.0)) bad("density", m.density, "use a positive density in kg/m^3");
  if (!(m.young > 0.0)) bad("young", m.young, "use a positive Young's modulus in Pa");
  // Linear elasticity is positive definite for -1 < nu < 0.5 (auxetic materials included).
  if (!(m.poisson > -1.0 && m.poisson < 0.5))
    bad("poisson", m.poisson, "use a Poisson ratio in (-1, 0.5)");
  if (!(m.alpha >= 0.0)) bad("alpha", m.alpha, "Rayleigh damping must not be negative");
  if (!(m.beta >= 0.0)) bad("beta", m.beta, "Rayleigh damping must not be negative");
}

}  // namespace

BodyModel compile_body(const TetMesh& mesh, const Material& material,
                       const std::vector<std::uint8_t>& pinned, const std::string& name) {
  check_material(material, name);
  validate_mesh(mesh, ("body '" + name + "'").c_str());
  if (!pinned.empty() && pinned.size() != mesh.x.size())
    throw std::runtime_error("body '" + name + "': " + std::to_string(pinned.size()) +
                             " pinned flags for " + std::to_string(mesh.x.size()) +
                             " nodes; give one flag per node or none");
  BodyModel b;
  b.name = name;
  b.material = material;
  b.rest = mesh.x;
  b.tets = mesh.tets;
  b.surface = boundary_faces(mesh.tets);
  b.pinned = pinned.empty() ? std::vector<std::uint8_t>(mesh.x.size(), 0) : pinned;
  b.mass.assign(mesh.x.size(), 0.0);
  b.dm_inv.resize(mesh.tets.size());
  b.volume.resize(mesh.tets.size());
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& e = mesh.tets[t];
    const Vec3d x0 = mesh.x[e.v[0]];
    const Mat3d dm =
        Mat3d::from_cols(mesh.x[e.v[1]] - x0, mesh.x[e.v[2]] - x0, mesh.x[e.v[3]] - x0);
    b.dm_inv[t] = inverse(dm);
    b.volume[t] = det(dm) / 6.0;
    // Lumped mass: a quarter of every tetrahedron's mass on each of its nodes.
    for (int a = 0; a < 4; ++a) b.mass[e.v[a]] += 0.25 * material.density * b.volume[t];
  }
  return b;
}

BodiesModel compile_bodies(std::vector<BodyModel> bodies, const FemSettings& s) {
  if (bodies.empty()) throw std::runtime_error("compile_bodies: no bodies");
  if (s.box && !(s.box_hi.x > s.box_lo.x && s.box_hi.y > s.box_lo.y && s.box_hi.z > s.box_lo.z))
    throw std::runtime_error("fem settings: box_hi must exceed box_lo on every axis");
  if (!(s.cg_tolerance > 0.0) || s.cg_max_iterations < 1 || s.rotation_iterations < 1 ||
      s.newton_iterations < 1)
    throw std::runtime_error(
        "fem settings: need cg_tolerance > 0 and cg_max_iterations, rotation_iterations, "
        "newton_iterations >= 1");
  if (!(s.friction >= 0.0)) throw std::runtime_error("fem settings: friction must be >= 0");

  BodiesModel m;
  m.settings = s;
  // Every array sized once: grown by push_back they kept up to twice their size for the run.
  std::size_t nodes = 0, tets = 0, tris = 0;
  for (const BodyModel& b : bodies) {
    nodes += b.rest.size();
    tets += b.tets.size();
    tris += b.surface.size();
  }
  for (auto* v : {&m.x0, &m.v0}) v->reserve(nodes);
  for (auto* v : {&m.mass, &m.alpha}) v->reserve(nodes);
  m.pinned.reserve(nodes);
  m.tets.reserve(tets);
  m.grad.reserve(3 * tets);
  for (auto* v : {&m.mu_vol, &m.lambda_vol, &m.beta}) v->reserve(tets);
  m.surface.reserve(tris);
  for (const BodyModel& b : bodies) {
    m.node_offset.push_back(m.nodes);
    m.tet_offset.push_back(m.elements);
    m.tri_offset.push_back(int(m.surface.size()));
    const double mu = lame_mu(b.material), lambda = lame_lambda(b.material);
    for (std::size_t i = 0; i < b.rest.size(); ++i) {
      m.x0.push_back(Vec3(b.rest[i]));
      m.v0.push_back(b.pinned[i] ? Vec3() : Vec3(b.velocity));
      m.mass.push_back(Real(b.mass[i]));
      m.alpha.push_back(Real(b.material.alpha));
      m.pinned.push_back(b.pinned[i]);
    }
    for (std::size_t t = 0; t < b.tets.size(); ++t) {
      Tet e = b.tets[t];
      for (int a = 0; a < 4; ++a) e.v[a] += m.nodes;
      m.tets.push_back(e);
      for (int r = 0; r < 3; ++r) m.grad.push_back(Vec3(b.dm_inv[t].row(r)));
      m.mu_vol.push_back(Real(mu * b.volume[t]));
      m.lambda_vol.push_back(Real(lambda * b.volume[t]));
      m.beta.push_back(Real(b.material.beta));
    }
    for (Tri f : b.surface) {
      for (int a = 0; a < 3; ++a) f.v[a] += m.nodes;
      m.surface.push_back(f);
    }
    m.nodes += int(b.rest.size());
    m.elements += int(b.tets.size());
  }
  m.node_offset.push_back(m.nodes);
  m.tet_offset.push_back(m.elements);
  m.tri_offset.push_back(int(m.surface.size()));

  // Gather lists (counting sort by node), in element order within each node.
  m.inc_start.assign(m.nodes + 1, 0);
  for (const Tet& e : m.tets)
    for (int a = 0; a < 4; ++a) ++m.inc_start[e.v[a] + 1];
  for (int i = 0; i < m.nodes; ++i) m.inc_start[i + 1] += m.inc_start[i];
  m.inc.resize(m.inc_start[m.nodes]);
  std::vector<int> fill(m.inc_start.begin(), m.inc_start.end() - 1);
  for (int t = 0; t < m.elements; ++t)
    for (int a = 0; a < 4; ++a) m.inc[fill[m.tets[t].v[a]]++] = t * 4 + a;

  m.bodies = std::move(bodies);
  return m;
}

}  // namespace sphfem
