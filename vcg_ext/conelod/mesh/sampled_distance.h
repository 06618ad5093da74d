// ConeLOD — the distance between two surfaces by sampling (a Metro-like Hausdorff distance), and
// the faces of a coarse mesh that face away from the surface they approximate.
//
// Cignoni, Rocchini, Scopigno, "Metro: measuring error on simplified surfaces" (1998): sample one
// surface (its vertices plus points spread over its faces in proportion to area) and take, for
// each sample, the distance to the closest point of the other surface (vcglib's uniform grid,
// GridStaticPtr). The Hausdorff distance is the larger of the two one-sided maxima. MeshLab's
// "Hausdorff Distance" filter does the same; this one runs without MeshLab, on IndexedMesh.
#pragma once

#include <algorithm>
#include <cstddef>

#include "conelod/mesh/indexed_mesh.h"
#include "conelod/status.h"

namespace conelod {

struct SurfaceDistance {
  double max = 0, mean = 0, rms = 0;  // model units
  size_t samples = 0;
};

// The most face samples one distance takes: 10 million samples already resolve a 0.01 % error on
// a 10-million-face mesh; far more only costs minutes (and crashed vcglib's grid search).
constexpr int kMaxFaceSamples = 10000000;

// One-sided: from points of `from` (its used vertices plus about `faceSamples` points on its
// faces, deterministic) to the surface of `to`.
Status SampledDistance(const IndexedMesh& from, const IndexedMesh& to, int faceSamples, SurfaceDistance& out);

// Both ways: ab = from a to b, ba = from b to a; hausdorff = max(ab.max, ba.max).
struct HausdorffResult {
  SurfaceDistance ab, ba;
  double hausdorff = 0;
  double diagonal = 0;  // bounding-box diagonal of `a`, to report distances as a fraction of it
  // The larger of the two directions' RMS and maximum, in % of `diagonal` (the comparisons'
  // measure: scripts/compare_qem.sh's, MeshLab's Hausdorff Distance both ways).
  double rmsPct() const { return 100 * std::max(ab.rms, ba.rms) / diagonal; }
  double maxPct() const { return 100 * std::max(ab.max, ba.max) / diagonal; }
};
Status SampledHausdorff(const IndexedMesh& a, const IndexedMesh& b, int faceSamples, HausdorffResult& out);

// Faces of `coarse` (non-degenerate) whose normal makes more than 90 degrees with the normal of the
// face of `reference` closest to the coarse face's centroid. Where the reference is thinner than
// the coarse mesh's error the closest face may lie on the other side, so this counts candidates,
// not proven flips.
size_t CountFacesAgainstSurface(const IndexedMesh& coarse, const IndexedMesh& reference);

}  // namespace conelod
