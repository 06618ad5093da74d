// ConeLOD — the parameters MeshLab 2020.09's "Simplification: Quadric Edge Collapse Decimation"
// runs vcglib's TriEdgeCollapseQuadric with by default. The plugin's budget filter and the
// simplification benchmark both run that built-in QEM and must use the same settings.
#pragma once

#include <vcg/complex/algorithms/local_optimization/tri_edge_collapse_quadric.h>

namespace conelod {

inline vcg::tri::TriEdgeCollapseQuadricParameter BuiltinQemParameters() {
  vcg::tri::TriEdgeCollapseQuadricParameter pp;
  pp.QualityThr = 0.3;
  pp.PreserveBoundary = false;
  pp.BoundaryQuadricWeight = pp.BoundaryQuadricWeight * 1.0;
  pp.PreserveTopology = false;
  pp.QualityWeight = false;
  pp.NormalCheck = false;
  pp.OptimalPlacement = true;
  pp.QualityQuadric = false;
  pp.QualityQuadricWeight = 0.001;
  return pp;
}

}  // namespace conelod
