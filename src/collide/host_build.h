// Host-side construction steps of the BVH: the binned-SAH tree and the surface topology
// (edge neighbours and vertex fans for pseudonormals). Both run once per build on the host;
// device callers copy their triangles over first.
#pragma once

#include <vector>

#include "sphfem/collide/traverse.h"

namespace sphfem::collide {

// A tree in the shared layout, ready to upload. Boxes are final for the given positions.
struct HostTree {
  std::vector<BvhNode> nodes;
  std::vector<int> parent;  // -1 at the root
  std::vector<int> leaves;  // node ids of the leaves
  std::vector<int> prims;   // triangle ids, leaf ranges index this
  int depth = 0;            // edges from the root to the deepest leaf
};

// Top-down binned SAH (Wald 2007, "On fast construction of SAH-based bounding volume
// hierarchies"): 16 bins per axis over the centroid bounds, leaves of at most max_leaf
// triangles, object-median splits below depth 32 so the depth stays bounded for any input.
// Children of a node are adjacent in the node array.
HostTree build_sah_tree(const Vec3* x, const Tri* tris, int ntris, int max_leaf = 4);

struct SurfaceTopology {
  std::vector<int> nbr;     // 3 per face: the face across edge k (corners k, k+1), or -1
  std::vector<int> vstart;  // nverts + 1 offsets into vfaces
  std::vector<int> vfaces;  // faces around each vertex
  int nverts = 0;
};

// Edge neighbours (an edge shared by exactly two faces; boundary and non-manifold edges
// get -1) and vertex fans. Throws std::invalid_argument on a negative vertex index.
SurfaceTopology surface_topology(const Tri* tris, int ntris);

}  // namespace sphfem::collide
