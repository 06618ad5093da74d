// ConeLOD — the out-of-core LOD build's temporary folder (issue 27; docs/scale.md): the finished
// levels of the cluster DAG are spilled there as soon as the level above them is built, and the
// writer reads them back one at a time, so the faces of only one or two levels are in memory at
// once. Internal to lod_dag.cpp / lod_writer.cpp (BuildLodFile with LodBuildParams::chunkFaces).
//
// The folder is `.NAME.conelod-lod-PID.XXXXXX` beside the output NAME (mkdtemp). It is removed
// with everything in it when the LodSpill is destroyed: after success, after a failure, when an
// exception unwinds through the build; RemoveLodSpillsOnSignal() removes it from a signal handler
// (`conelod lod build` calls it on SIGINT, SIGTERM and SIGHUP). Only SIGKILL leaves it behind.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <vcg/space/box3.h>

#include "conelod/lod/lod_build.h"
#include "conelod/status.h"

namespace conelod {

class LodSpill {
 public:
  LodSpill() = default;
  LodSpill(const LodSpill&) = delete;
  LodSpill& operator=(const LodSpill&) = delete;
  ~LodSpill() { remove(); }

  // Creates the folder beside `outputPath`. "" or "cannot write 'FOLDER': why".
  std::string create(const std::string& outputPath);
  const std::string& folder() const { return folder_; }
  // Removes the level files and the folder (nothing when never created).
  void remove();

  // Writes level k's faces and faceCluster to the folder and frees them in L (its per-cluster
  // fields stay); also records the box of the positions its faces use (the writer's grid).
  Status put(size_t k, LodDag::Level& L, const std::vector<vcg::Point3f>& positions);
  bool has(size_t k) const { return k < faces_.size() && faces_[k] != kNone; }
  uint64_t faceCount(size_t k) const { return faces_[k]; }
  const vcg::Box3f& box(size_t k) const { return boxes_[k]; }
  // Reads level k's faces and faceCluster back.
  Status get(size_t k, std::vector<std::array<uint32_t, 3>>& faces, std::vector<uint32_t>& faceCluster) const;

 private:
  static constexpr uint64_t kNone = ~uint64_t(0);
  std::string file(size_t k) const;
  std::string folder_;
  std::vector<uint64_t> faces_;
  std::vector<vcg::Box3f> boxes_;
};

// BuildLodDag of a mesh it takes (its positions and faces become the DAG's level 0 without a
// copy; `mesh` is left empty), spilling each finished level to `spill` when given (its faces are
// then in the spill, not in the DAG). The DAG is the one BuildLodDag builds from the same mesh
// (with the same `attributes`, per vertex of `mesh`, optional).
Status BuildLodDagOwned(IndexedMesh&& mesh, const LodBuildParams& params, LodDag& out, const Progress& progress,
                        size_t* chunks, LodSpill* spill, const LodAttributes* attributes = nullptr);

// WriteLodFile of a DAG whose levels may be in `spill` (null: all in the DAG): the same bytes.
// inputVertices: the DAG's input vertices (all used); box: their box (UsedVertexBox).
Status WriteLodFileFrom(const LodDag& dag, const LodSpill* spill, size_t inputVertices, size_t inputFaces,
                        const vcg::Box3d& box, const std::string& path, LodBuildStats* stats, const Progress& progress,
                        double precision);

// Async-signal-safe: removes the level files and the folder of the spill being used, if any.
void RemoveLodSpillsOnSignal();

}  // namespace conelod
