// ConeLOD — is a triangle mesh a consistently oriented 2-manifold? (for the outputs of the
// simplifiers: a collapse must never create a non-manifold edge or vertex, or flip an edge's
// orientation).
#pragma once

#include <cstddef>

#include "conelod/mesh/indexed_mesh.h"

namespace conelod {

struct ManifoldReport {
  size_t nonManifoldEdges = 0;     // edges on three or more faces
  size_t nonManifoldVertices = 0;  // vertices whose faces do not form one fan (pinches), edges fine
  size_t misorientedEdges = 0;     // edges on two faces that run them the same way
  size_t degenerateFaces = 0;      // repeated vertex or zero area
  size_t borderEdges = 0;
  bool valid() const { return nonManifoldEdges == 0 && nonManifoldVertices == 0 && misorientedEdges == 0; }
};

// Indices must be valid (see mesh_check.h).
ManifoldReport CheckManifold(const IndexedMesh& m);

}  // namespace conelod
