// Vertex-face and edge-edge contact between body surfaces (sphfem/fem/contact.h): candidates
// from a host BVH over the faces' swept boxes (through a near list kept between steps while
// the surfaces move slowly), positions projected apart by Gauss-Seidel sweeps, then inelastic
// impulses with Coulomb friction on the pairs that touched.
#include "sphfem/fem/contact.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "collide/host_build.h"
#include "sphfem/collide/geometry.h"
#include "sphfem/fem/import.h"

namespace sphfem {

namespace {

// Six times the signed volume of element t at positions y: positive when its fourth node lies
// on the side its first three's normal (y1 - y0) x (y2 - y0) points to.
Real six_volume(const std::vector<Vec3>& y, const Tet& t) {
  const int* v = t.v;
  return dot(cross(y[v[1]] - y[v[0]], y[v[2]] - y[v[0]]), y[v[3]] - y[v[0]]);
}

using collide::BvhNode;

Real box_area(const Vec3& lo, const Vec3& hi) {
  const Vec3 d = hi - lo;
  return d.x * d.y + d.y * d.z + d.z * d.x;
}

bool overlaps(const BvhNode& n, const Vec3& lo, const Vec3& hi) {
  return !(n.hi.x < lo.x || n.hi.y < lo.y || n.hi.z < lo.z || n.lo.x > hi.x || n.lo.y > hi.y ||
           n.lo.z > hi.z);
}

// Calls visit(node) for each leaf whose box overlaps [lo, hi].
template <class Visit>
void leaves_overlapping(const std::vector<BvhNode>& tree, const Vec3& lo, const Vec3& hi,
                        Visit&& visit) {
  int stack[128];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const int i = stack[--sp];
    const BvhNode& n = tree[i];
    if (!overlaps(n, lo, hi)) continue;
    if (collide::is_leaf(n)) {
      visit(i);
    } else if (sp + 2 <= 128) {
      stack[sp++] = n.b;
      stack[sp++] = n.a;
    }
  }
}

bool differ(const Vec3& a, const Vec3& b) { return a.x != b.x || a.y != b.y || a.z != b.z; }

// The corners' barycentric weights of the point of face (a, b, c) closest to p.
struct Foot {
  Vec3 n;          // unit normal (0 for a degenerate face)
  Real d = 0;      // signed distance of p from the face's plane
  Real w[3] = {};  // weights of a, b, c
  Real lateral2 = 0;
};

Foot foot(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  Foot r;
  r.n = collide::unit_normal(a, b, c);
  r.d = dot(p - a, r.n);
  const collide::ClosestOnTriangle q = collide::closest_on_triangle(p, a, b, c);
  r.w[0] = Real(1) - q.u - q.v, r.w[1] = q.u, r.w[2] = q.v;
  r.lateral2 = std::max(Real(0), norm2(p - q.point) - r.d * r.d);
  return r;
}

Real unit_clamp(Real v) { return v < Real(0) ? Real(0) : v > Real(1) ? Real(1) : v; }

// Parameters s, t in [0, 1] of the closest points of segments p0 p1 and q0 q1 (Ericson,
// "Real-Time Collision Detection", 5.1.9).
void closest_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, Real& s,
                      Real& t) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const Real a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
  s = t = Real(0);
  if (!(a > Real(0)) || !(e > Real(0))) return;
  const Real c = dot(d1, r), b = dot(d1, d2), den = a * e - b * b;
  s = den > Real(0) ? unit_clamp((b * f - c * e) / den) : Real(0);
  t = (b * s + f) / e;
  if (t < Real(0)) {
    t = Real(0);
    s = unit_clamp(-c / a);
  } else if (t > Real(1)) {
    t = Real(1);
    s = unit_clamp((b - c) / a);
  }
}

// The vector between the closest points of edges E and G at positions y (from G's to E's),
// and their parameters s, t.
Vec3 between_edges(const std::vector<Vec3>& y, const std::array<int, 2>& E,
                   const std::array<int, 2>& G, Real& s, Real& t) {
  closest_segments(y[E[0]], y[E[1]], y[G[0]], y[G[1]], s, t);
  return y[E[0]] + (y[E[1]] - y[E[0]]) * s - y[G[0]] - (y[G[1]] - y[G[0]]) * t;
}

}  // namespace

double SurfaceContact::default_gap(const BodiesModel& m) {
  std::vector<Real> len;
  len.reserve(m.surface.size() * 3);
  for (const Tri& t : m.surface)
    for (int k = 0; k < 3; ++k) len.push_back(norm(m.x0[t.v[k]] - m.x0[t.v[(k + 1) % 3]]));
  if (len.empty()) return 0.0;
  std::nth_element(len.begin(), len.begin() + len.size() / 2, len.end());
  return 0.1 * double(len[len.size() / 2]);
}

SurfaceContact::SurfaceContact(const BodiesModel& m, const ContactSettings& s) {
  if (!(s.gap >= 0) || !(s.friction >= 0))
    throw std::invalid_argument("contact: gap and friction must be >= 0");
  gap_ = s.gap > 0 ? s.gap : default_gap(m);
  friction_ = s.friction;
  rounds_ = std::max(1, s.rounds);
  sweeps_ = std::max(1, s.sweeps);
  x0_ = m.x0;
  tris_ = m.surface;
  const int nb = int(m.bodies.size());
  node_body_.assign(std::size_t(m.nodes), 0);
  tri_body_.assign(tris_.size(), 0);
  for (int b = 0; b < nb; ++b) {
    for (int i = m.node_offset[b]; i < m.node_offset[b + 1]; ++i) node_body_[i] = b;
    for (int t = m.tri_offset[b]; t < m.tri_offset[b + 1]; ++t) tri_body_[t] = b;
  }
  std::vector<std::uint8_t> on(std::size_t(m.nodes), 0);
  for (const Tri& t : tris_)
    for (int k = 0; k < 3; ++k) on[t.v[k]] = 1;
  for (int i = 0; i < m.nodes; ++i)
    if (on[i]) verts_.push_back(i);
  // Unique edges, and each face's three.
  std::vector<std::array<int, 3>> keyed;  // (low node, high node, face * 3 + corner)
  for (std::size_t f = 0; f < tris_.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = tris_[f].v[k], b = tris_[f].v[(k + 1) % 3];
      keyed.push_back({std::min(a, b), std::max(a, b), int(f) * 3 + k});
    }
  std::sort(keyed.begin(), keyed.end());
  tri_edges_.resize(tris_.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    if (i == 0 || keyed[i][0] != keyed[i - 1][0] || keyed[i][1] != keyed[i - 1][1])
      edges_.push_back({keyed[i][0], keyed[i][1]});
    tri_edges_[keyed[i][2] / 3][keyed[i][2] % 3] = int(edges_.size()) - 1;
  }
  std::vector<int> face_of(std::size_t(m.nodes), -1);
  for (std::size_t f = tris_.size(); f-- > 0;)
    for (int k = 0; k < 3; ++k) face_of[tris_[f].v[k]] = int(f);
  for (int p : verts_) vert_face_.push_back(face_of[p]);
  face_edge_.resize(tris_.size());
  for (std::size_t f = 0; f < tris_.size(); ++f) {
    Real l = 0;
    for (int k = 0; k < 3; ++k)
      l = std::max(l, norm(x0_[tris_[f].v[k]] - x0_[tris_[f].v[(k + 1) % 3]]));
    face_edge_[f] = l;
  }
  // The surface graph: each node's neighbours along surface edges, sorted.
  ring_start_.assign(std::size_t(m.nodes) + 1, 0);
  for (const std::array<int, 2>& e : edges_) ++ring_start_[e[0] + 1], ++ring_start_[e[1] + 1];
  for (int i = 0; i < m.nodes; ++i) ring_start_[i + 1] += ring_start_[i];
  ring_.resize(std::size_t(ring_start_.back()));
  {
    std::vector<int> at(ring_start_.begin(), ring_start_.end() - 1);
    for (const std::array<int, 2>& e : edges_) ring_[at[e[0]]++] = e[1], ring_[at[e[1]]++] = e[0];
    for (int i = 0; i < m.nodes; ++i)
      std::sort(ring_.begin() + ring_start_[i], ring_.begin() + ring_start_[i + 1]);
  }
  node_face_start_.assign(std::size_t(m.nodes) + 1, 0);
  for (const Tri& t : tris_)
    for (int k = 0; k < 3; ++k) ++node_face_start_[t.v[k] + 1];
  for (int i = 0; i < m.nodes; ++i) node_face_start_[i + 1] += node_face_start_[i];
  node_faces_.resize(std::size_t(node_face_start_.back()));
  {
    std::vector<int> at(node_face_start_.begin(), node_face_start_.end() - 1);
    for (std::size_t f = 0; f < tris_.size(); ++f)
      for (int k = 0; k < 3; ++k) node_faces_[at[tris_[f].v[k]]++] = int(f);
  }
  edge_face_.assign(edges_.size(), -1);
  for (std::size_t f = tris_.size(); f-- > 0;)
    for (int e : tri_edges_[f]) edge_face_[e] = int(f);
  edge_face_start_.assign(edges_.size() + 1, 0);
  for (const std::array<int, 3>& te : tri_edges_)
    for (int e : te) ++edge_face_start_[e + 1];
  for (std::size_t e = 0; e < edges_.size(); ++e) edge_face_start_[e + 1] += edge_face_start_[e];
  edge_faces_.resize(std::size_t(edge_face_start_.back()));
  std::vector<int> fill(edge_face_start_.begin(), edge_face_start_.end() - 1);
  for (std::size_t f = 0; f < tris_.size(); ++f)
    for (int e : tri_edges_[f]) edge_faces_[fill[e]++] = int(f);
  inv_mass_.resize(std::size_t(m.nodes));
  for (int i = 0; i < m.nodes; ++i)
    inv_mass_[i] = m.pinned[i] || !(m.mass[i] > Real(0)) ? Real(0) : Real(1) / m.mass[i];
  // Each node's height over the opposite face of its elements at rest, the least of them: a
  // push of the node by as much toward that face turns the element inside out.
  height_.assign(std::size_t(m.nodes), std::numeric_limits<Real>::max());
  for (const Tet& t : m.tets)
    for (int k = 0; k < 4; ++k) {
      const Vec3 &a = x0_[t.v[(k + 1) % 4]], &b = x0_[t.v[(k + 2) % 4]], &c = x0_[t.v[(k + 3) % 4]];
      const Vec3 n = cross(b - a, c - a);
      const Real area2 = norm(n);
      if (area2 > Real(0))
        height_[t.v[k]] = std::min(height_[t.v[k]], std::fabs(dot(x0_[t.v[k]] - a, n)) / area2);
    }
  // The elements, their rest volumes and each node's elements, for the volume floor.
  tets_ = m.tets;
  rest_det_.resize(tets_.size());
  for (std::size_t t = 0; t < tets_.size(); ++t) rest_det_[t] = six_volume(x0_, tets_[t]);
  node_tet_start_.assign(std::size_t(m.nodes) + 1, 0);
  for (const Tet& t : tets_)
    for (int v : t.v) ++node_tet_start_[v + 1];
  for (int i = 0; i < m.nodes; ++i) node_tet_start_[i + 1] += node_tet_start_[i];
  node_tets_.resize(std::size_t(node_tet_start_.back()));
  {
    std::vector<int> at(node_tet_start_.begin(), node_tet_start_.end() - 1);
    for (std::size_t t = 0; t < tets_.size(); ++t)
      for (int v : tets_[t].v) node_tets_[at[v]++] = int(t);
  }
  box_ = m.settings.box;
  box_lo_ = Vec3(m.settings.box_lo);
  box_hi_ = Vec3(m.settings.box_hi);
  if (!tris_.empty()) build_tree(x0_);
}

// A binned-SAH tree over the faces at x, its boxes, and the box area later refits compare with.
void SurfaceContact::build_tree(const std::vector<Vec3>& x) {
  collide::HostTree t = collide::build_sah_tree(x.data(), tris_.data(), int(tris_.size()));
  tree_ = std::move(t.nodes);
  prims_ = std::move(t.prims);
  leaves_ = std::move(t.leaves);
  // Each query to the leaf that holds its face, in query order within a leaf.
  std::vector<int> leaf_of(tris_.size());
  face_leaf_.resize(tris_.size());
  leaf_ord_.assign(tree_.size(), -1);
  for (std::size_t l = 0; l < leaves_.size(); ++l) {
    leaf_ord_[leaves_[l]] = int(l);
    const BvhNode& n = tree_[leaves_[l]];
    for (int k = n.a; k < n.a - n.b; ++k)
      leaf_of[prims_[k]] = int(l), face_leaf_[prims_[k]] = leaves_[l];
  }
  const int nv = int(verts_.size()), nq = nv + int(edges_.size());
  auto face = [&](int q) { return q < nv ? vert_face_[q] : edge_face_[q - nv]; };
  home_start_.assign(leaves_.size() + 1, 0);
  for (int q = 0; q < nq; ++q) ++home_start_[leaf_of[face(q)] + 1];
  for (std::size_t l = 0; l < leaves_.size(); ++l) home_start_[l + 1] += home_start_[l];
  home_.resize(std::size_t(nq));
  std::vector<int> fill(home_start_.begin(), home_start_.end() - 1);
  for (int q = 0; q < nq; ++q) home_[fill[leaf_of[face(q)]]++] = q;
  refit(x, x);
  area0_ = tree_area();
}

double SurfaceContact::tree_area() const {
  double a = 0;
  for (const BvhNode& n : tree_) a += box_area(n.lo, n.hi);
  return a;
}

// Leaf boxes hold each face at both ends of the step, grown by the gap; parents their
// children. A top-down build puts children after their parent, so a backward pass suffices.
void SurfaceContact::refit(const std::vector<Vec3>& x_old, const std::vector<Vec3>& x) {
  const Vec3 g{Real(gap_), Real(gap_), Real(gap_)};
  for (int i = int(tree_.size()) - 1; i >= 0; --i) {
    BvhNode& n = tree_[i];
    if (collide::is_leaf(n)) {
      Vec3 lo = x[tris_[prims_[n.a]].v[0]], hi = lo;
      for (int k = n.a; k < n.a - n.b; ++k)
        for (int c = 0; c < 3; ++c) {
          const int v = tris_[prims_[k]].v[c];
          lo = vmin(lo, vmin(x_old[v], x[v]));
          hi = vmax(hi, vmax(x_old[v], x[v]));
        }
      n.lo = lo - g, n.hi = hi + g;
    } else {
      n.lo = vmin(tree_[n.a].lo, tree_[n.b].lo);
      n.hi = vmax(tree_[n.a].hi, tree_[n.b].hi);
    }
  }
}

// Nodes a and b at most two surface edges apart.
bool SurfaceContact::two_rings(int a, int b) const {
  if (a == b) return true;
  const int *A = ring_.data() + ring_start_[a], *Ae = ring_.data() + ring_start_[a + 1];
  const int *B = ring_.data() + ring_start_[b], *Be = ring_.data() + ring_start_[b + 1];
  if (std::binary_search(A, Ae, b)) return true;
  while (A != Ae && B != Be) {  // a common neighbour
    if (*A == *B) return true;
    *A < *B ? ++A : ++B;
  }
  return false;
}

// Same-body pairs closer at rest than three gaps never count (kNever). Nor do those closer
// than the longer rest edge of the two with a node of one at most two surface edges from a
// node of the other (kSheet), unless the surface has folded so that their sides face each other
// (facing): a surface squeezed along itself brings a vertex within the gap of a face one or two
// rings away, and pushing it off its own sheet wrinkles the surface and inverts elements, but a
// wall buckled into a crease presses its neighbouring rings together and must hold them apart. Pair
// (p, f) as in Pair; the radii are scaled by shrink (the near list keeps a margin).
SurfaceContact::Rest SurfaceContact::rest_neighbours(int p, int f, Real shrink) const {
  if (f >= 0) {
    if (node_body_[p] != tri_body_[f]) return kApart;
    const Tri& t = tris_[f];
    const Vec3 q =
        collide::closest_on_triangle(x0_[p], x0_[t.v[0]], x0_[t.v[1]], x0_[t.v[2]]).point;
    const Real d2 = norm2(x0_[p] - q), g = shrink * Real(3 * gap_), r = shrink * face_edge_[f];
    Rest near = kApart;
    if (d2 < g * g)
      near = kNever;
    else if (d2 < r * r && (two_rings(p, t.v[0]) || two_rings(p, t.v[1]) || two_rings(p, t.v[2])))
      near = kSheet;
    return near != kApart && crevice_gap(p, f) > Real(0) ? kCrevice : near;
  }
  const std::array<int, 2>&E = edges_[p], &G = edges_[-f - 1];
  if (node_body_[E[0]] != node_body_[G[0]]) return kApart;
  Real s, t;
  const Real d2 = norm2(between_edges(x0_, E, G, s, t)), g = shrink * Real(3 * gap_);
  if (d2 < g * g) return kNever;
  const Real r = shrink * std::max(norm(x0_[E[1]] - x0_[E[0]]), norm(x0_[G[1]] - x0_[G[0]]));
  if (d2 < r * r && (two_rings(E[0], G[0]) || two_rings(E[0], G[1]) || two_rings(E[1], G[0]) ||
                     two_rings(E[1], G[1])))
    return kSheet;
  return kApart;
}

// Whether the surface around pair (p, f) has turned its two sides toward each other at x: a
// face around the vertex (or of the edge) and the face (or a face of the other edge) whose
// normals point against each other, by a cosine half a unit lower than at rest and below 0.
// A sheet squeezed along itself keeps its normals together, and a crevice of the rest shape
// keeps its own angle; a crease, or a corner crushed to an acute angle, closes them.
bool SurfaceContact::facing(int p, int f, const std::vector<Vec3>& x) const {
  auto normal = [&](const std::vector<Vec3>& y, int t) {
    const Tri& T = tris_[t];
    return cross(y[T.v[1]] - y[T.v[0]], y[T.v[2]] - y[T.v[0]]);
  };
  auto cosine = [](const Vec3& a, const Vec3& b) {
    const Real l = norm(a) * norm(b);
    return l > Real(0) ? dot(a, b) / l : Real(1);
  };
  auto against = [&](const int* a, const int* ae, const int* b, const int* be) {
    for (const int* i = a; i != ae; ++i)
      for (const int* j = b; j != be; ++j) {
        const Real now = cosine(normal(x, *i), normal(x, *j));
        if (now < Real(0) && now < cosine(normal(x0_, *i), normal(x0_, *j)) - Real(0.5))
          return true;
      }
    return false;
  };
  if (f >= 0)
    return against(node_faces_.data() + node_face_start_[p],
                   node_faces_.data() + node_face_start_[p + 1], &f, &f + 1);
  const int g = -f - 1;
  return against(
      edge_faces_.data() + edge_face_start_[p], edge_faces_.data() + edge_face_start_[p + 1],
      edge_faces_.data() + edge_face_start_[g], edge_faces_.data() + edge_face_start_[g + 1]);
}

// A same-body vertex p that lay across a crevice from face f at rest: in front of it and over
// it (within 45 degrees of its normal), as the two sides of a scanned bunny's lip do, a gap
// or two apart. Closing the crevice is the body's business, crossing it is not: such a pair
// counts however close it lay, and keeps half its rest distance (or the gap, if less), so
// nothing is pushed at rest. 0 for any other pair.
Real SurfaceContact::crevice_gap(int p, int f) const {
  const Tri& t = tris_[f];
  const Vec3 n = collide::unit_normal(x0_[t.v[0]], x0_[t.v[1]], x0_[t.v[2]]);
  const Vec3 w =
      x0_[p] - collide::closest_on_triangle(x0_[p], x0_[t.v[0]], x0_[t.v[1]], x0_[t.v[2]]).point;
  const Real d = dot(w, n);
  if (!(d > Real(0)) || norm2(w) > 2 * d * d) return Real(0);
  return std::min(Real(gap_), Real(0.5) * d);
}

// Whether pair (p, f) may count at x, as far as rest neighbours go, and the distance it keeps.
bool SurfaceContact::may_touch(int p, int f, const std::vector<Vec3>& x, Real& keep) const {
  const Rest r = rest_neighbours(p, f, Real(1));
  keep = r == kCrevice ? crevice_gap(p, f) : Real(gap_);
  return r == kApart || r == kCrevice || (r == kSheet && facing(p, f, x));
}

// Vertex p is in contact with face f when it lies within the gap in front of the face, or
// behind it no deeper than the vertex moved relative to the face's corners this step (a
// motion the two share crosses nothing), unless it started the step behind the
// face and over it (then it is inside for another reason and must not be pulled through; a
// vertex beside the face, behind its plane, may slide under it within a step on a wavy
// surface). Faces that touch p never count, nor its rest neighbours unless folded to face it.
bool SurfaceContact::vertex_face(int p, int f, const std::vector<Vec3>& x_old,
                                 const std::vector<Vec3>& x, Real& keep) const {
  const Tri& t = tris_[f];
  if (t.v[0] == p || t.v[1] == p || t.v[2] == p) return false;
  // Tested with the common gap first, then with the pair's own (never larger).
  const Foot e = foot(x[p], x[t.v[0]], x[t.v[1]], x[t.v[2]]);
  const Foot s = foot(x_old[p], x_old[t.v[0]], x_old[t.v[1]], x_old[t.v[2]]);
  auto touches = [&](Real g) {
    if (!(e.d < g) || e.lateral2 > g * g || norm2(e.n) == Real(0)) return false;
    if (s.d < -g && s.lateral2 <= g * g) return false;
    if (e.d < Real(0)) {
      const Vec3 dp = x[p] - x_old[p];
      Real rel = 0;
      for (int k = 0; k < 3; ++k) rel = std::max(rel, norm(dp - (x[t.v[k]] - x_old[t.v[k]])));
      if (-e.d > rel + g) return false;
    }
    return true;
  };
  if (!touches(Real(gap_)) || !may_touch(p, f, x, keep)) return false;
  return keep == Real(gap_) || touches(keep);
}

// Edges e and g (sharing no node, not rest neighbours unfolded)
// are in contact when their closest points, inside both, lie within the gap along the
// direction that separated them at the step's start, or behind it no deeper than one edge's
// nodes moved relative to the other's. Ends of edges are the vertex-face test's.
bool SurfaceContact::edge_edge(int e, int g, const std::vector<Vec3>& x_old,
                               const std::vector<Vec3>& x, Vec3& n) const {
  const std::array<int, 2>&E = edges_[e], &G = edges_[g];
  if (E[0] == G[0] || E[0] == G[1] || E[1] == G[0] || E[1] == G[1]) return false;
  const Real gap = Real(gap_);
  Real s, t;
  const Vec3 w = between_edges(x, E, G, s, t);
  if (!(s > Real(0) && s < Real(1) && t > Real(0) && t < Real(1))) return false;
  Real s0, t0;
  const Vec3 w0 = between_edges(x_old, E, G, s0, t0);
  const Real len0 = norm(w0);
  if (!(len0 > Real(1e-3) * gap)) return false;  // touching at the start: no side to keep
  n = w0 / len0;
  const Real d = dot(w, n);
  if (!(d < gap) || norm2(w) - d * d > gap * gap) return false;
  if (d < Real(0)) {
    Real rel = 0;
    for (int a : E)
      for (int b : G) rel = std::max(rel, norm((x[a] - x_old[a]) - (x[b] - x_old[b])));
    if (-d > rel + gap) return false;
  }
  Real keep;
  return may_touch(e, -g - 1, x, keep);
}

// The pair at positions x: its nodes, their weights (+ on the side the normal points to), the
// normal and the signed distance. False for a face without area.
bool SurfaceContact::contact(const Pair& c, const std::vector<Vec3>& x, Contact& out) const {
  if (c.f >= 0) {
    const Tri& t = tris_[c.f];
    const Foot e = foot(x[c.p], x[t.v[0]], x[t.v[1]], x[t.v[2]]);
    if (norm2(e.n) == Real(0)) return false;
    out =
        Contact{{c.p, t.v[0], t.v[1], t.v[2]}, {Real(1), -e.w[0], -e.w[1], -e.w[2]}, e.n, e.d, c.g};
    return true;
  }
  const std::array<int, 2>&E = edges_[c.p], &G = edges_[-c.f - 1];
  Real s, t;
  const Vec3 w = between_edges(x, E, G, s, t);
  out = Contact{{E[0], E[1], G[0], G[1]}, {Real(1) - s, s, t - Real(1), -t}, c.n, dot(w, c.n), c.g};
  return true;
}

// Calls vertex(p, f, out) for each face f of the leaves whose boxes overlap vertex p's swept
// box grown by `grow`, and edge(e, g, out) for each edge g > e (once, ascending) of the faces
// of the leaves overlapping edge e's; out is the calling thread's part of found_. A query's
// box lies inside its home leaf's box, so only the leaves overlapping that one (grown) need
// testing: one tree walk per leaf, not per query.
template <class Vertex, class Edge>
void SurfaceContact::each_candidate(const std::vector<Vec3>& x_old, const std::vector<Vec3>& x,
                                    Real grow, Vertex&& vertex, Edge&& edge) {
  const int nv = int(verts_.size()), nl = int(leaves_.size());
  const int nt = omp_get_max_threads();
  if (found_.size() < std::size_t(nt)) found_.resize(std::size_t(nt));
  for (std::vector<Pair>& f : found_) f.clear();
  const Vec3 r{grow, grow, grow};
#pragma omp parallel num_threads(nt)
  {
    std::vector<Pair>& mine = found_[std::size_t(omp_get_thread_num())];
    std::vector<int> near_leaves, near;
#pragma omp for schedule(dynamic, 16)
    for (int l = 0; l < nl; ++l) {
      const BvhNode& home = tree_[leaves_[l]];
      near_leaves.clear();
      leaves_overlapping(tree_, home.lo - r, home.hi + r, [&](int i) { near_leaves.push_back(i); });
      for (int h = home_start_[l]; h < home_start_[l + 1]; ++h) {
        const int q = home_[h];
        if (q < nv) {
          const int p = verts_[q];
          const Vec3 lo = vmin(x_old[p], x[p]) - r, hi = vmax(x_old[p], x[p]) + r;
          for (int i : near_leaves) {
            const BvhNode& n = tree_[i];
            if (overlaps(n, lo, hi))
              for (int k = n.a; k < n.a - n.b; ++k) vertex(p, prims_[k], mine);
          }
          continue;
        }
        const int e = q - nv;
        const int a = edges_[e][0], b = edges_[e][1];
        const Vec3 lo = vmin(vmin(x_old[a], x[a]), vmin(x_old[b], x[b])) - r;
        const Vec3 hi = vmax(vmax(x_old[a], x[a]), vmax(x_old[b], x[b])) + r;
        near.clear();
        for (int i : near_leaves) {
          const BvhNode& n = tree_[i];
          if (!overlaps(n, lo, hi)) continue;
          for (int k = n.a; k < n.a - n.b; ++k)
            for (int g : tri_edges_[prims_[k]])
              if (g > e) near.push_back(g);
        }
        std::sort(near.begin(), near.end());
        near.erase(std::unique(near.begin(), near.end()), near.end());
        for (int g : near) edge(e, g, mine);
      }
    }
  }
}

// The pairs found, in index order (faces by index, not by the tree's order: the sweeps' order
// then survives a rebuild, and a checkpoint, which starts from the rest tree).
void SurfaceContact::gather(std::vector<Pair>& out) const {
  for (const std::vector<Pair>& m : found_) out.insert(out.end(), m.begin(), m.end());
  std::sort(out.begin(), out.end(),
            [](const Pair& a, const Pair& b) { return a.p != b.p ? a.p < b.p : a.f < b.f; });
}

// The near list (contact.h): every pair of the surfaces within kSkin gaps at x, less the pairs
// that never count (sharing a node, or rest neighbours: those by a margin, the test decides
// the others). The tree's leaves hold the faces at x grown by the gap, so queries grown by the
// skin less 0.9 gaps find every face within it.
void SurfaceContact::list_near(const std::vector<Vec3>& x_old, const std::vector<Vec3>& x,
                               Real skin) {
  const Real keep2 = skin * skin;
  each_candidate(
      x_old, x, skin - Real(0.9 * gap_),
      [&](int p, int f, std::vector<Pair>& out) {
        const Tri& t = tris_[f];
        if (t.v[0] == p || t.v[1] == p || t.v[2] == p) return;
        const Vec3 q = collide::closest_on_triangle(x[p], x[t.v[0]], x[t.v[1]], x[t.v[2]]).point;
        if (!(norm2(x[p] - q) <= keep2)) return;
        if (rest_neighbours(p, f, Real(0.99)) == kNever) return;
        out.push_back({p, f, Vec3(), Real(0)});
      },
      [&](int e, int g, std::vector<Pair>& out) {
        const std::array<int, 2>&E = edges_[e], &G = edges_[g];
        if (E[0] == G[0] || E[0] == G[1] || E[1] == G[0] || E[1] == G[1]) return;
        Real s, t;
        if (!(norm2(between_edges(x, E, G, s, t)) <= keep2)) return;
        if (rest_neighbours(e, -g - 1, Real(0.99)) == kNever) return;
        out.push_back({e, -g - 1, Vec3(), Real(0)});
      });
  near_.clear();
  gather(near_);
  x_ref_ = x;
  listed_ = true;
}

// Vertex-face and edge-edge pairs in contact at x, in index order: the pairs the tree's boxes
// propose (each_candidate) that pass vertex_face or edge_edge. With the near list, the same
// pairs come from three sources, each through the tree's own box test: the listed pairs (all
// pairs whose nodes are slow), the queries with a fast node against every leaf, and every
// query against the leaves holding a fast node.
void SurfaceContact::detect(const std::vector<Vec3>& x_old, const std::vector<Vec3>& x,
                            std::vector<Pair>& out) {
  out.clear();
  if (tree_.empty()) return;
  auto test_vertex = [&](int p, int f, std::vector<Pair>& o) {
    Real keep;
    if (vertex_face(p, f, x_old, x, keep)) o.push_back({p, f, Vec3(), keep});
  };
  auto test_edge = [&](int e, int h, std::vector<Pair>& o) {
    Vec3 n;
    if (edge_edge(e, h, x_old, x, n)) o.push_back({e, -h - 1, n, Real(gap_)});
  };
  const int nv = int(verts_.size()), nl = int(leaves_.size());
  // A pair in contact lies within sqrt(g^2 + (g + 4 m)^2) at x when none of its nodes moved
  // more than m in the step (vertex_face, edge_edge), and that distance changed by at most
  // 2 d since x_ref_ when none drifted more than d: such pairs are listed. The slack covers
  // the distances' round-off.
  const Real g = Real(gap_), skin = Real(kSkin) * g, slow = Real(kSlow) * g;
  Real scale = 0;
  int fast = 0;
  for (int p : verts_) {
    for (int c = 0; c < 3; ++c) scale = std::max(scale, std::fabs(x[p][c]));
    fast += norm(x[p] - x_old[p]) > slow;
  }
  const Real slack = Real(1e-3) * skin + Real(1e-5) * scale;
  const Real reach = std::sqrt(g * g + (g + 4 * slow) * (g + 4 * slow));
  const Real drift = (skin - reach - slack) / 2;
  if (4 * fast > nv || !(drift > 0)) {  // moving too fast for a list to pay
    listed_ = false;
    each_candidate(x_old, x, Real(0), test_vertex, test_edge);
    gather(out);
    return;
  }
  // Drift is measured past the nodes' mean shift since x_ref_: a shift common to all nodes
  // changes no distance.
  auto mark = [&] {
    Vec3 shift;
    for (int p : verts_) shift += (x[p] - x_ref_[p]) / Real(nv);
    int n = 0;
    for (int p : verts_) {
      fast_[p] = norm(x[p] - x_old[p]) > slow || norm(x[p] - x_ref_[p] - shift) > drift;
      n += fast_[p];
    }
    return n;
  };
  fast_.resize(x.size());
  if (!listed_ || 4 * mark() > nv) {
    list_near(x_old, x, skin);
    mark();
  }
  leaf_fast_.assign(std::size_t(nl), 0);
  for (int l = 0; l < nl; ++l) {
    const BvhNode& n = tree_[leaves_[l]];
    for (int k = n.a; k < n.a - n.b; ++k)
      for (int c = 0; c < 3; ++c) leaf_fast_[l] |= fast_[tris_[prims_[k]].v[c]];
  }
  const int nn = int(near_.size()), nt = omp_get_max_threads();
  if (found_.size() < std::size_t(nt)) found_.resize(std::size_t(nt));
  for (std::vector<Pair>& f : found_) f.clear();
  auto box_of = [&](int q, Vec3& lo, Vec3& hi) {  // query q's swept box; true when fast
    if (q < nv) {
      const int p = verts_[q];
      lo = vmin(x_old[p], x[p]), hi = vmax(x_old[p], x[p]);
      return fast_[p] != 0;
    }
    const int a = edges_[q - nv][0], b = edges_[q - nv][1];
    lo = vmin(vmin(x_old[a], x[a]), vmin(x_old[b], x[b]));
    hi = vmax(vmax(x_old[a], x[a]), vmax(x_old[b], x[b]));
    return fast_[a] || fast_[b];
  };
#pragma omp parallel num_threads(nt)
  {
    std::vector<Pair>& mine = found_[std::size_t(omp_get_thread_num())];
    // The listed pairs, each as the tree would propose it.
#pragma omp for schedule(static) nowait
    for (int i = 0; i < nn; ++i) {
      const Pair& c = near_[i];
      if (c.f >= 0) {
        const Vec3 lo = vmin(x_old[c.p], x[c.p]), hi = vmax(x_old[c.p], x[c.p]);
        if (overlaps(tree_[face_leaf_[c.f]], lo, hi)) test_vertex(c.p, c.f, mine);
        continue;
      }
      const int e = c.p, h = -c.f - 1;
      Vec3 lo, hi;
      box_of(nv + e, lo, hi);
      bool proposed = false;
      for (int k = edge_face_start_[h]; k < edge_face_start_[h + 1] && !proposed; ++k)
        proposed = overlaps(tree_[face_leaf_[edge_faces_[k]]], lo, hi);
      if (proposed) test_edge(e, h, mine);
    }
    // Queries with a fast node against every leaf their box meets, and every query against
    // the fast leaves its box meets (a query's box lies in its home leaf's).
    std::vector<int> near_leaves, near;
    auto edges_of = [&](int e, const BvhNode& n) {
      for (int k = n.a; k < n.a - n.b; ++k)
        for (int h : tri_edges_[prims_[k]])
          if (h > e) near.push_back(h);
    };
    auto test_near = [&](int e) {
      std::sort(near.begin(), near.end());
      near.erase(std::unique(near.begin(), near.end()), near.end());
      for (int h : near) test_edge(e, h, mine);
    };
#pragma omp for schedule(dynamic, 16)
    for (int l = 0; l < nl; ++l) {
      bool any = leaf_fast_[l] != 0;
      Vec3 lo, hi;
      for (int k = home_start_[l]; k < home_start_[l + 1] && !any; ++k)
        any = box_of(home_[k], lo, hi);
      if (!any) continue;
      const BvhNode& home = tree_[leaves_[l]];
      near_leaves.clear();
      leaves_overlapping(tree_, home.lo, home.hi, [&](int i) { near_leaves.push_back(i); });
      for (int k = home_start_[l]; k < home_start_[l + 1]; ++k) {
        const int q = home_[k];
        if (!box_of(q, lo, hi)) continue;
        near.clear();
        for (int i : near_leaves) {
          const BvhNode& n = tree_[i];
          if (!overlaps(n, lo, hi)) continue;
          if (q < nv)
            for (int j = n.a; j < n.a - n.b; ++j) test_vertex(verts_[q], prims_[j], mine);
          else
            edges_of(q - nv, n);
        }
        if (q >= nv) test_near(q - nv);
      }
      if (!leaf_fast_[l]) continue;
      for (int i : near_leaves) {
        const int a = leaf_ord_[i];
        for (int k = home_start_[a]; k < home_start_[a + 1]; ++k) {
          const int q = home_[k];
          if (box_of(q, lo, hi) || !overlaps(home, lo, hi)) continue;  // fast: done above
          if (q < nv) {
            for (int j = home.a; j < home.a - home.b; ++j) test_vertex(verts_[q], prims_[j], mine);
          } else {
            near.clear();
            edges_of(q - nv, home);
            test_near(q - nv);
          }
        }
      }
    }
  }
  gather(out);
  out.erase(std::unique(out.begin(), out.end(),
                        [](const Pair& a, const Pair& b) { return a.p == b.p && a.f == b.f; }),
            out.end());
}

ContactStats SurfaceContact::resolve(const std::vector<Vec3>& x_old, std::vector<Vec3>& x,
                                     std::vector<Vec3>& v, double dt,
                                     std::vector<std::uint8_t>& moved) {
  ContactStats st;
  moved.assign(x.size(), 0);
  if (tree_.empty() || !(dt > 0)) return st;
  const Real g = Real(gap_), mu = Real(friction_);
  const std::vector<Vec3> x_in = x, v_in = v;
  auto clamp = [&](int i) {  // the tank's walls win: a push never leaves a node outside
    if (!box_) return;
    for (int c = 0; c < 3; ++c) {
      if (x[i][c] < box_lo_[c]) x[i][c] = box_lo_[c], v[i][c] = std::max(v[i][c], Real(0));
      if (x[i][c] > box_hi_[c]) x[i][c] = box_hi_[c], v[i][c] = std::min(v[i][c], Real(0));
    }
  };
  // Positions: each pair pushed to the gap along its normal, the push shared by inverse mass
  // and weight (momentum-free: the weights sum to zero).
  std::vector<Pair> pairs, touched;
  Contact k;
  auto weight = [&](const Contact& c) {
    Real W = 0;
    for (int i = 0; i < 4; ++i) W += c.w[i] * c.w[i] * inv_mass_[c.node[i]];
    return W;
  };
  // The volume floor: each element of a node pushed deeper than kDeepPush of its height keeps
  // 6 V >= floor_det_, oriented as at rest: kKeepVolume of its rest volume, or what it had
  // before the pushes if less. A unilateral constraint projected like a push (Müller et al.
  // 2007's volume constraint): its gradients sum to zero, so it is momentum-free too.
  watched_.resize(tets_.size(), 0);  // all 0: each call clears what it set
  floor_det_.resize(tets_.size());
  squeezed_.clear();
  auto oriented_det = [&](int t, const std::vector<Vec3>& y) {
    const Real d = six_volume(y, tets_[t]);
    return rest_det_[t] < Real(0) ? -d : d;
  };
  auto watch = [&](int node) {
    for (int k = node_tet_start_[node]; k < node_tet_start_[node + 1]; ++k) {
      const int t = node_tets_[k];
      if (watched_[t]) continue;
      watched_[t] = 1;
      squeezed_.push_back(t);
      floor_det_[t] = std::min(Real(kKeepVolume) * std::fabs(rest_det_[t]), oriented_det(t, x_in));
    }
  };
  bool floored = false;
  auto keep_volume = [&](int t) {
    const int* n = tets_[t].v;
    const Real d = oriented_det(t, x);
    if (!(d < floor_det_[t])) return;
    const Real o = rest_det_[t] < Real(0) ? Real(-1) : Real(1);
    const Vec3 e1 = x[n[1]] - x[n[0]], e2 = x[n[2]] - x[n[0]], e3 = x[n[3]] - x[n[0]];
    Vec3 grad[4];
    grad[1] = cross(e2, e3) * o, grad[2] = cross(e3, e1) * o, grad[3] = cross(e1, e2) * o;
    grad[0] = -(grad[1] + grad[2] + grad[3]);
    Real S = 0;
    for (int i = 0; i < 4; ++i) S += inv_mass_[n[i]] * norm2(grad[i]);
    if (!(S > Real(0))) return;
    const Real lambda = (floor_det_[t] - d) / S;
    floored = true;
    for (int i = 0; i < 4; ++i) {
      if (!(inv_mass_[n[i]] > Real(0))) continue;
      x[n[i]] += grad[i] * (lambda * inv_mass_[n[i]]);
      clamp(n[i]);
    }
  };
  double area = 0;
  for (; st.rounds < rounds_; ++st.rounds) {
    refit(x_old, x);
    if (st.rounds == 0) area = tree_area();
    detect(x_old, x, pairs);
    bool violated = false;
    for (const Pair& c : pairs)
      if (contact(c, x, k) && k.d < k.g * Real(0.999)) {
        violated = true;
        if (st.rounds == 0) {
          Real h = std::numeric_limits<Real>::max();
          for (int i = 0; i < 4; ++i)
            if (k.w[i] != Real(0)) h = std::min(h, height_[k.node[i]]);
          st.depth_ratio = std::max(st.depth_ratio, double((k.g - k.d) / h));
        }
      }
    if (!violated) break;
    touched.insert(touched.end(), pairs.begin(), pairs.end());
    // Pushes and volume floors pull against each other where a push reaches through an
    // element: rounds where a floor acted sweep up to four times as often.
    floored = false;
    for (int s = 0; s < sweeps_ || (floored && s < 4 * sweeps_); ++s) {
      for (const Pair& c : pairs) {
        if (!contact(c, x, k) || !(k.d < k.g)) continue;
        const Real W = weight(k);
        if (!(W > Real(0))) continue;
        const Vec3 push = k.n * ((k.g - k.d) / W);
        for (int i = 0; i < 4; ++i) {
          x[k.node[i]] += push * (k.w[i] * inv_mass_[k.node[i]]);
          clamp(k.node[i]);
          if (k.w[i] != Real(0) && inv_mass_[k.node[i]] > Real(0) &&
              k.g - k.d > Real(kDeepPush) * height_[k.node[i]])
            watch(k.node[i]);
        }
      }
      for (std::size_t t = 0; t < squeezed_.size(); ++t) keep_volume(squeezed_[t]);
    }
  }
  for (int t : squeezed_) watched_[t] = 0;
  // A deformed tree answers slowly: rebuild it over the current surface now and then.
  if (area > 2.0 * area0_) build_tree(x);

  // Velocities: the pairs that touched stop approaching (inelastic), and their tangential
  // motion loses mu times the normal impulse (Coulomb, sticking when that suffices).
  std::stable_sort(touched.begin(), touched.end(),
                   [](const Pair& a, const Pair& b) { return a.p != b.p ? a.p < b.p : a.f < b.f; });
  touched.erase(std::unique(touched.begin(), touched.end(),
                            [](const Pair& a, const Pair& b) { return a.p == b.p && a.f == b.f; }),
                touched.end());
  for (int s = 0; s < sweeps_; ++s)
    for (const Pair& c : touched) {
      if (!contact(c, x, k) || !(k.d < Real(2) * k.g)) continue;
      const Real W = weight(k);
      Vec3 rel;
      for (int i = 0; i < 4; ++i) rel += v[k.node[i]] * k.w[i];
      const Real un = dot(rel, k.n);
      if (!(un < Real(0)) || !(W > Real(0))) continue;
      const Real jn = -un / W;
      const Vec3 ut = rel - k.n * un;
      const Real slide = norm(ut);
      const Real jt = std::min(slide / W, mu * jn);
      Vec3 j = k.n * jn;
      if (slide > Real(0)) j -= ut * (jt / slide);
      for (int i = 0; i < 4; ++i) {
        v[k.node[i]] += j * (k.w[i] * inv_mass_[k.node[i]]);
        clamp(k.node[i]);
      }
    }

  st.pairs = int(touched.size());
  for (const Pair& c : touched)
    if (contact(c, x, k)) st.min_gap = std::min(st.min_gap, double(k.d * g / k.g));
  for (std::size_t i = 0; i < x.size(); ++i)
    if (differ(x[i], x_in[i]) || differ(v[i], v_in[i])) moved[i] = 1, ++st.nodes;
  return st;
}

long intersecting_pairs(const BodiesModel& m, const std::vector<Vec3>& x) {
  SurfaceMesh s;
  s.x.reserve(x.size());
  for (const Vec3& p : x) s.x.push_back(Vec3d(p));
  s.tris = m.surface;
  return count_self_intersections(s);
}

int inverted_elements(const BodiesModel& m, const std::vector<Vec3>& x) {
  int n = 0;
  for (const Tet& t : m.tets)
    if (!(six_volume(x, t) * six_volume(m.x0, t) > Real(0))) ++n;
  return n;
}

}  // namespace sphfem
