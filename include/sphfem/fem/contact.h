// Contact between body surfaces: a body touching itself (a fold, a crushed foot) or another
// body. Vertex-face pairs over all bodies' surface triangles, resolved after each implicit
// step, on the host, so that every backend shares one implementation.
//
// The response is a split impulse (as in rigid-body engines): positions are pushed apart to
// the gap without a velocity of their own, so closing an overlap creates no kinetic energy;
// velocities get inelastic normal impulses with Coulomb friction, each shared between the
// vertex and the face's corners by their barycentric weights and inverse masses, so total
// momentum is exact up to round-off. Vertex-face and edge-edge pairs are both tested. The
// guarantee is bounded penetration, not none: a crossing within the step is caught when its
// depth is within what the surfaces moved that step (docs/design.md).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "sphfem/collide/traverse.h"
#include "sphfem/fem/model.h"

namespace sphfem {

struct ContactSettings {
  double gap = 0;         // m, the distance kept between a vertex and a face; 0: default_gap
  double friction = 0.5;  // Coulomb coefficient between the surfaces
  int rounds = 4;         // detections per step (a push may make new contacts)
  int sweeps = 4;         // Gauss-Seidel sweeps over the contacts per detection
};

struct ContactStats {
  int pairs = 0;   // vertex-face pairs pushed apart or stopped this step
  int rounds = 0;  // detections run
  int nodes = 0;   // nodes whose position or velocity changed
  // m, the smallest signed distance among the pairs after the response (negative: a vertex
  // still behind a face), each scaled to the common gap from its own (a crevice's pair keeps
  // less, contact.cpp); +inf when no pair was near.
  double min_gap = std::numeric_limits<double>::infinity();
  // The deepest pair found before the response, over the least rest height of its nodes'
  // elements (a push that deep can turn an element inside out at 1).
  double depth_ratio = 0;
};

class SurfaceContact {
 public:
  // Throws std::invalid_argument for a negative gap or friction.
  SurfaceContact(const BodiesModel& model, const ContactSettings& settings);

  double gap() const { return gap_; }

  // A step from x_old to x (v the velocities after it), dt seconds: pairs found and resolved
  // in place. moved[i] is set for each node changed (sized to the node count).
  ContactStats resolve(const std::vector<Vec3>& x_old, std::vector<Vec3>& x, std::vector<Vec3>& v,
                       double dt, std::vector<std::uint8_t>& moved);

  // A tenth of the median surface edge at rest.
  static double default_gap(const BodiesModel& model);

 private:
  // A vertex p against face f, or (f < 0) edge p against edge -f - 1 (edges_ indices), with
  // an edge pair's normal fixed at the step's start, and the distance the pair keeps.
  struct Pair {
    int p, f;
    Vec3 n;
    Real g;
  };
  // Four nodes with weights summing to zero, the normal, the signed distance along it and
  // the distance to keep.
  struct Contact {
    int node[4];
    Real w[4];
    Vec3 n;
    Real d, g;
  };
  void build_tree(const std::vector<Vec3>& x);
  double tree_area() const;
  void refit(const std::vector<Vec3>& x_old, const std::vector<Vec3>& x);
  void detect(const std::vector<Vec3>& x_old, const std::vector<Vec3>& x, std::vector<Pair>& out);
  template <class Vertex, class Edge>
  void each_candidate(const std::vector<Vec3>& x_old, const std::vector<Vec3>& x, Real grow,
                      Vertex&& vertex, Edge&& edge);
  void gather(std::vector<Pair>& out) const;
  void list_near(const std::vector<Vec3>& x_old, const std::vector<Vec3>& x, Real skin);
  bool vertex_face(int p, int f, const std::vector<Vec3>& x_old, const std::vector<Vec3>& x,
                   Real& keep) const;
  bool edge_edge(int e, int g, const std::vector<Vec3>& x_old, const std::vector<Vec3>& x,
                 Vec3& n) const;
  bool contact(const Pair& c, const std::vector<Vec3>& x, Contact& out) const;
  enum Rest { kApart, kSheet, kNever, kCrevice };  // how a same-body pair lay at rest
  Rest rest_neighbours(int p, int f, Real shrink) const;
  Real crevice_gap(int p, int f) const;
  bool two_rings(int a, int b) const;
  bool facing(int p, int f, const std::vector<Vec3>& x) const;
  bool may_touch(int p, int f, const std::vector<Vec3>& x, Real& keep) const;

  std::vector<Vec3> x0_;  // rest positions: same-body faces near a vertex at rest never count
  std::vector<Tri> tris_;
  std::vector<Real> face_edge_;  // each face's longest edge at rest
  std::vector<int> tri_body_, node_body_, verts_;
  std::vector<std::array<int, 2>> edges_;          // unique surface edges
  std::vector<int> ring_start_, ring_;             // each node's surface neighbours, sorted
  std::vector<int> node_face_start_, node_faces_;  // each node's surface faces
  std::vector<std::array<int, 3>> tri_edges_;
  std::vector<Real> inv_mass_;  // 0 on pinned nodes
  std::vector<Real> height_;    // per node, its least height over an element's opposite face
  // A node pushed deeper than kDeepPush of its height keeps each of its elements at
  // kKeepVolume of its rest volume at least (or what it had before the pushes, if less):
  // unilateral volume constraints swept with the contacts (resolve), so a push through a thin
  // element's height moves the nodes behind it instead of turning the element inside out.
  static constexpr double kKeepVolume = 0.2, kDeepPush = 0.25;
  std::vector<Tet> tets_;
  std::vector<Real> rest_det_;                   // per tet, 6 times its rest volume (signed)
  std::vector<int> node_tet_start_, node_tets_;  // each node's elements
  std::vector<int> squeezed_;                    // elements the pushes reached this step
  std::vector<Real> floor_det_;                  // per tet, the least 6 V kept this step
  std::vector<std::uint8_t> watched_;            // per tet, in squeezed_
  std::vector<collide::BvhNode> tree_;
  std::vector<int> prims_;
  // The queries grouped by the leaf that holds a face of theirs (a vertex's first face, an
  // edge's face), whose box contains their swept boxes: the leaves near it, found by one walk,
  // serve all its queries. home_[home_start_[l]..home_start_[l + 1]) for leaf leaves_[l]:
  // vertex j (verts_ index) as j, edge e as verts_.size() + e.
  std::vector<int> leaves_, home_start_, home_;
  std::vector<int> leaf_ord_;                      // leaves_ index of each tree node, -1 inside
  std::vector<int> face_leaf_;                     // the tree node of each face's leaf
  std::vector<int> vert_face_, edge_face_;         // a face of each vertex (verts_ order), edge
  std::vector<int> edge_face_start_, edge_faces_;  // the faces of each edge
  std::vector<std::vector<Pair>> found_;           // per thread, kept between detections
  // The near list (a Verlet list, as molecular dynamics keeps its neighbours): the pairs
  // within kSkin gaps of each other at x_ref_, less those that never count. A pair whose
  // nodes are slow (moved at most kSlow gaps this step and drifted little since x_ref_) can
  // only touch if it is listed, so only the list, the fast nodes' queries and the fast
  // nodes' leaves are tested; the pairs found are the same. A cache: a checkpoint needs none.
  static constexpr double kSkin = 5.0, kSlow = 0.4;
  std::vector<Pair> near_;
  std::vector<Vec3> x_ref_;
  std::vector<std::uint8_t> fast_, leaf_fast_;  // per node, per leaf (leaves_ order)
  bool listed_ = false;
  double area0_ = 0;
  double gap_ = 0, friction_ = 0;
  int rounds_ = 4, sweeps_ = 4;
  bool box_ = false;
  Vec3 box_lo_, box_hi_;
};

// Elements whose signed volume at x does not have its sign at rest.
int inverted_elements(const BodiesModel& model, const std::vector<Vec3>& x);
// Pairs of the bodies' surface triangles that intersect at x, by the exact test of
// fem/import.h (count_self_intersections), independent of the contact's own.
long intersecting_pairs(const BodiesModel& model, const std::vector<Vec3>& x);

}  // namespace sphfem
