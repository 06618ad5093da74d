// ConeLOD MeshLab plugin — MeshLab's own "Simplification: Quadric Edge Collapse Decimation", run
// from inside this plugin (the budget filter offers it as a simplifier).
//
// MeshLab 2020.09's filter_meshing runs vcglib's tri::TriEdgeCollapseQuadric on CMeshO with a
// per-vertex quadric kept in a temporary attribute; this is the same collapse type, the same
// parameters as that filter's defaults (QualityThr 0.3, OptimalPlacement, no boundary, normal,
// topology or planar constraints, AutoClean) and the same post-processing, so the result matches
// the built-in filter run with TargetFaceNum = the budget.
#pragma once

#include "meshlab_api.h"
#include <vcg/complex/algorithms/clean.h>
#include <vcg/complex/algorithms/local_optimization.h>
#include <vcg/complex/algorithms/local_optimization/tri_edge_collapse_quadric.h>

#include "conelod/simplify/builtin_qem_params.h"

namespace conelod_plugin {

using QuadricTemp = vcg::SimpleTempData<CMeshO::VertContainer, vcg::math::Quadric<double>>;

// Where the collapse type finds each vertex's quadric (CMeshO has no quadric member).
class QuadricHelper {
 public:
  static void Init() {}
  static vcg::math::Quadric<double>& Qd(CVertexO& v) { return TD()[v]; }
  static vcg::math::Quadric<double>& Qd(CVertexO* v) { return TD()[*v]; }
  static CVertexO::ScalarType W(CVertexO*) { return 1.0; }
  static CVertexO::ScalarType W(CVertexO&) { return 1.0; }
  static void Merge(CVertexO&, CVertexO const&) {}
  static QuadricTemp*& TDp() {
    static QuadricTemp* td = nullptr;
    return td;
  }
  static QuadricTemp& TD() { return *TDp(); }
};

using QemVertexPair = vcg::tri::BasicVertexPair<CVertexO>;

class QemCollapse : public vcg::tri::TriEdgeCollapseQuadric<CMeshO, QemVertexPair, QemCollapse, QuadricHelper> {
 public:
  using Base = vcg::tri::TriEdgeCollapseQuadric<CMeshO, QemVertexPair, QemCollapse, QuadricHelper>;
  QemCollapse(const QemVertexPair& p, int i, vcg::BaseParameterClass* pp) : Base(p, i, pp) {}
};

// Simplifies `mm` to `targetFaces` faces; returns the faces removed by the post-clean.
inline int RunBuiltinQuadric(MeshModel& mm, int targetFaces, vcg::CallBackPos* cb) {
  CMeshO& m = mm.cm;
  mm.updateDataMask(MeshModel::MM_VERTFACETOPO | MeshModel::MM_VERTMARK);
  vcg::tri::UpdateFlags<CMeshO>::FaceBorderFromVF(m);

  vcg::tri::TriEdgeCollapseQuadricParameter pp = conelod::BuiltinQemParameters();

  vcg::math::Quadric<double> zero;
  zero.SetZero();
  QuadricTemp td(m.vert, zero);
  QuadricHelper::TDp() = &td;
  vcg::LocalOptimization<CMeshO> session(m, &pp);
  if (cb) cb(1, "Initializing simplification");
  session.Init<QemCollapse>();
  session.SetTargetSimplices(targetFaces);
  session.SetTimeBudget(0.1f);
  const int toDelete = std::max(1, m.fn - targetFaces);
  while (session.DoOptimization() && m.fn > targetFaces)
    if (cb) cb(100 - 100 * (m.fn - targetFaces) / toDelete, "Simplifying...");
  session.Finalize<QemCollapse>();
  QuadricHelper::TDp() = nullptr;

  // AutoClean, as the built-in filter does.
  const int nullFaces = vcg::tri::Clean<CMeshO>::RemoveFaceOutOfRangeArea(m, 0);
  vcg::tri::Clean<CMeshO>::RemoveDuplicateVertex(m);
  vcg::tri::Clean<CMeshO>::RemoveUnreferencedVertex(m);
  mm.clearDataMask(MeshModel::MM_FACEFACETOPO);
  vcg::tri::Allocator<CMeshO>::CompactVertexVector(m);
  vcg::tri::Allocator<CMeshO>::CompactFaceVector(m);
  UpdateBoxAndNormals(mm);
  return nullFaces;
}

}  // namespace conelod_plugin
