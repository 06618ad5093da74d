// MeshLab's "Quadric Edge Collapse Decimation" as the benchmarks' peer: vcglib's
// tri::TriEdgeCollapseQuadric on the vertex/face types of vcglib's decimation sample (tridecimator:
// VF adjacency, mark, a quadric per vertex) with MeshLab 2020.09's filter defaults
// (conelod::BuiltinQemParameters). The plugin runs the same collapse on MeshLab's own mesh type
// (filter_conelod/builtin_qem.h).
#pragma once

#include <vector>

#include <vcg/complex/complex.h>
#include <vcg/complex/algorithms/local_optimization.h>
#include <vcg/complex/algorithms/local_optimization/tri_edge_collapse_quadric.h>

#include "conelod/simplify/builtin_qem_params.h"

namespace conelod_bench {

class QVertex;
class QFace;
struct QUsedTypes : public vcg::UsedTypes<vcg::Use<QVertex>::AsVertexType, vcg::Use<QFace>::AsFaceType> {};
class QVertex : public vcg::Vertex<QUsedTypes, vcg::vertex::VFAdj, vcg::vertex::Coord3f, vcg::vertex::Normal3f,
                                   vcg::vertex::Mark, vcg::vertex::Qualityf, vcg::vertex::BitFlags> {
 public:
  vcg::math::Quadric<double>& Qd() { return q_; }

 private:
  vcg::math::Quadric<double> q_;
};
class QFace : public vcg::Face<QUsedTypes, vcg::face::VFAdj, vcg::face::VertexRef, vcg::face::Normal3f,
                               vcg::face::Qualityf, vcg::face::BitFlags> {};
class QMesh : public vcg::tri::TriMesh<std::vector<QVertex>, std::vector<QFace>> {};
using QPair = vcg::tri::BasicVertexPair<QVertex>;
class QCollapse : public vcg::tri::TriEdgeCollapseQuadric<QMesh, QPair, QCollapse, vcg::tri::QInfoStandard<QVertex>> {
 public:
  using Base = vcg::tri::TriEdgeCollapseQuadric<QMesh, QPair, QCollapse, vcg::tri::QInfoStandard<QVertex>>;
  QCollapse(const QPair& p, int mark, vcg::BaseParameterClass* pp) : Base(p, mark, pp) {}
};

// Simplifies `m` in place to `targetFaces` faces (or as close as the collapse gets); returns the
// faces left. No post-clean: the benchmarks compare the collapse itself.
inline size_t RunMeshLabQem(QMesh& m, size_t targetFaces) {
  vcg::tri::UpdateTopology<QMesh>::VertexFace(m);
  vcg::tri::UpdateFlags<QMesh>::FaceBorderFromVF(m);
  vcg::tri::TriEdgeCollapseQuadricParameter pp = conelod::BuiltinQemParameters();
  vcg::LocalOptimization<QMesh> session(m, &pp);
  session.Init<QCollapse>();
  session.SetTargetSimplices(int(targetFaces));
  session.SetTimeBudget(0.1f);
  while (session.DoOptimization() && size_t(m.fn) > targetFaces) {
  }
  session.Finalize<QCollapse>();
  return size_t(m.fn);
}

}  // namespace conelod_bench
