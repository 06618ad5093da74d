// ConeLOD — a big group-preserving simplification in spatial parts, on every core.
//
// SimplifyPreservingGroups (group_qem.h) runs on one core and holds ~325 bytes per input face. A
// mesh of at least PartitionParams::minFaces faces is instead cut into parts along group contours
// (recursive median cuts of the groups' centroids, weighted by their faces, so that every group
// lies in ONE part and the parts have about the same number of faces), each part is simplified on
// its own to its share of the target (target / input faces x its faces), on `threads` threads,
// with the vertices it shares with other parts frozen (GroupQemRegion: they do not move and no
// edge at them collapses, so the parts never touch each other's faces and every other vertex sees
// its whole neighbourhood). The parts are stitched in input order, and a final pass of the same
// collapse over the stitched mesh, with the caller's parameters, reaches the target: the seams
// still have the input's density, so their edges are the cheapest, and the pass takes the seams
// down to about the density of the rest. Every group stays whole as in the serial run: a group
// lies in one part, and the final pass is the serial collapse itself.
//
// The cut depends on the mesh and the parameters only, never on the thread count, and the parts
// are stitched in a fixed order: the result is the same for any number of threads.
#pragma once

#include <cstddef>
#include <vector>

#include "conelod/mesh/indexed_mesh.h"
#include "conelod/simplify/group_qem.h"
#include "conelod/status.h"

namespace conelod {

struct PartitionParams {
  // Meshes with at least this many faces are simplified in parts; 0: never.
  size_t minFaces = 2000000;
  // About this many faces per part (the part count is a power of two, 2 to kMaxPartitions).
  size_t facesPerPart = 1000000;
  int threads = 0;  // threads that simplify the parts; 0: one per core. The result does not depend on it.
};
constexpr int kMaxPartitions = 64;

// What the partitioned run did (all zero when it ran in one piece).
struct PartitionStats {
  int parts = 0;                              // parts simplified side by side (0: one piece)
  size_t frozenVertices = 0;                  // vertices shared by two parts (frozen while the parts run)
  size_t facesAfterParts = 0;                 // faces of the stitched mesh, before the final pass
  size_t finalPassCollapses = 0;              // collapses of the final pass
  double partsSeconds = 0, finalSeconds = 0;  // wall: the parts (with the cut and the stitch), the final pass
  // CPU seconds of the parts' threads: all parts, and the largest part (on an otherwise idle
  // machine the parts take about max(partsCpuSeconds / threads, largestPartCpuSeconds)).
  double partsCpuSeconds = 0, largestPartCpuSeconds = 0;
};

// The part count SimplifyPartitioned uses for `faces` faces with `params` (1: one piece, serial).
// Attributes, coarser groupings and a region run in one piece (SimplifyPreservingGroups).
int PartitionCount(size_t faces, const GroupQemParams& qem, const PartitionParams& params);

// As SimplifyPreservingGroups(mesh, faceGroup, qem, out, progress) — same output layout (faces and
// vertices in input order, sourceFace/sourceVertex into `mesh`) — in parts when PartitionCount > 1,
// else exactly SimplifyPreservingGroups. `stats` (optional) tells what the parts did. Progress is
// reported on the calling thread only.
Status SimplifyPartitioned(const IndexedMesh& mesh, const std::vector<int>& faceGroup, const GroupQemParams& qem,
                           const PartitionParams& params, GroupQemResult& out, const Progress& progress = Progress(),
                           PartitionStats* stats = nullptr);

}  // namespace conelod
