// ConeLOD — welding vertices at identical positions (weld.h).
#include "conelod/mesh/weld.h"

#include <algorithm>
#include <array>
#include <cstring>

#include "conelod/parallel.h"

namespace conelod {
namespace {

// The bits of a coordinate, -0 as +0 (they are the same position).
uint32_t Bits(float x) {
  if (x == 0) x = 0;
  uint32_t u;
  std::memcpy(&u, &x, 4);
  return u;
}

// Sorts the keys (distinct: each holds its vertex) as std::sort does: on `threads` threads, a
// piece each, then the sorted pieces merged pairwise (the order is total, so the result is the
// same for every thread count).
void SortKeys(std::vector<std::array<uint32_t, 4>>& keys, unsigned threads) {
  constexpr size_t kMinPiece = size_t(1) << 15;
  const size_t pieces = std::max<size_t>(1, std::min<size_t>(threads, keys.size() / kMinPiece));
  if (pieces <= 1) {
    std::sort(keys.begin(), keys.end());
    return;
  }
  std::vector<size_t> bound(pieces + 1);
  for (size_t i = 0; i <= pieces; ++i) bound[i] = keys.size() * i / pieces;
  ParallelChunks(pieces, unsigned(pieces), 1, [&](size_t begin, size_t end, unsigned) {
    for (size_t i = begin; i < end; ++i) std::sort(keys.begin() + long(bound[i]), keys.begin() + long(bound[i + 1]));
  });
  for (size_t width = 1; width < pieces; width *= 2) {
    const size_t merges = (pieces + 2 * width - 1) / (2 * width);
    ParallelChunks(merges, unsigned(std::min<size_t>(threads, merges)), 1, [&](size_t begin, size_t end, unsigned) {
      for (size_t m = begin; m < end; ++m) {
        const size_t lo = 2 * width * m, mid = std::min(pieces, lo + width), hi = std::min(pieces, lo + 2 * width);
        if (mid < hi)
          std::inplace_merge(keys.begin() + long(bound[lo]), keys.begin() + long(bound[mid]),
                             keys.begin() + long(bound[hi]));
      }
    });
  }
}

}  // namespace

WeldResult WeldByPosition(const IndexedMesh& in) {
  WeldResult r;
  const size_t V = in.positions.size();
  if (in.faces.empty()) {  // nothing to weld: as it is, so that the checks' messages count its vertices
    r.mesh = in;
    r.representative.resize(V);
    for (uint32_t i = 0; i < V; ++i) r.representative[i] = i;
    return r;
  }
  std::vector<uint8_t> used(V, 0);
  for (const auto& t : in.faces)
    for (uint32_t v : t) {
      if (v >= V) {  // not a mesh to weld: as it is, for RequireValidForFaces to refuse it
        r.mesh = in;
        r.representative.resize(V);
        for (uint32_t i = 0; i < V; ++i) r.representative[i] = i;
        return r;
      }
      used[v] = 1;
    }
  // Used vertices sorted by (position bits, index): equal positions stand together, lowest index
  // first.
  std::vector<std::array<uint32_t, 4>> keys;
  keys.reserve(V);
  for (uint32_t v = 0; v < V; ++v)
    if (used[v]) {
      const vcg::Point3f& p = in.positions[v];
      keys.push_back({{Bits(p[0]), Bits(p[1]), Bits(p[2]), v}});
    }
  r.droppedVertices = V - keys.size();
  std::sort(keys.begin(), keys.end());
  // Each input vertex -> its representative; representatives numbered in input order.
  std::vector<uint32_t> repOf(V, UINT32_MAX);
  for (size_t i = 0; i < keys.size();) {
    size_t j = i;
    while (j < keys.size() && keys[j][0] == keys[i][0] && keys[j][1] == keys[i][1] && keys[j][2] == keys[i][2]) {
      repOf[keys[j][3]] = keys[i][3];
      ++j;
    }
    r.mergedVertices += j - i - 1;
    i = j;
  }
  std::vector<uint32_t> newId(V, UINT32_MAX);
  for (uint32_t v = 0; v < V; ++v)
    if (used[v] && repOf[v] == v) {
      newId[v] = uint32_t(r.representative.size());
      r.representative.push_back(v);
      r.mesh.positions.push_back(in.positions[v]);
    }
  r.mesh.faces.reserve(in.faces.size());
  for (const auto& t : in.faces) r.mesh.faces.push_back({newId[repOf[t[0]]], newId[repOf[t[1]]], newId[repOf[t[2]]]});
  return r;
}

bool WeldByPositionInPlace(IndexedMesh& mesh, size_t* merged, size_t* dropped, unsigned threads) {
  const size_t V = mesh.positions.size();
  if (merged) *merged = 0;
  if (dropped) *dropped = 0;
  if (mesh.faces.empty()) return false;
  if (V >= 0x80000000u) {  // ids below are marked with their top bit
    for (const auto& t : mesh.faces)
      for (uint32_t v : t)
        if (v >= V) return false;
    WeldResult r = WeldByPosition(mesh);
    mesh = std::move(r.mesh);
    if (merged) *merged = r.mergedVertices;
    if (dropped) *dropped = r.droppedVertices;
    return true;
  }
  std::vector<uint32_t> repOf(V, UINT32_MAX);  // first: 1 marks a used vertex
  for (const auto& t : mesh.faces)
    for (uint32_t v : t) {
      if (v >= V) return false;
      repOf[v] = 1;
    }
  std::vector<std::array<uint32_t, 4>> keys;  // as WeldByPosition
  keys.reserve(V);
  for (uint32_t v = 0; v < V; ++v)
    if (repOf[v] == 1) {
      const vcg::Point3f& p = mesh.positions[v];
      keys.push_back({{Bits(p[0]), Bits(p[1]), Bits(p[2]), v}});
    }
  if (dropped) *dropped = V - keys.size();
  SortKeys(keys, threads);
  std::fill(repOf.begin(), repOf.end(), UINT32_MAX);
  size_t mergedCount = 0;
  for (size_t i = 0; i < keys.size();) {
    size_t j = i;
    while (j < keys.size() && keys[j][0] == keys[i][0] && keys[j][1] == keys[i][1] && keys[j][2] == keys[i][2]) {
      repOf[keys[j][3]] = keys[i][3];
      ++j;
    }
    mergedCount += j - i - 1;
    i = j;
  }
  if (merged) *merged = mergedCount;
  std::vector<std::array<uint32_t, 4>>().swap(keys);
  // Representatives keep their input order, so a vertex's new id is at most its old one: the
  // positions compact in place.
  uint32_t next = 0;
  for (uint32_t v = 0; v < V; ++v)
    if (repOf[v] == v) {
      mesh.positions[next] = mesh.positions[v];
      repOf[v] = next++ | 0x80000000u;  // a representative's new id, marked
    }
  for (auto& t : mesh.faces)
    for (uint32_t& v : t) {
      const uint32_t r = repOf[v];
      v = (r & 0x80000000u) ? (r & 0x7FFFFFFFu) : (repOf[r] & 0x7FFFFFFFu);
    }
  mesh.positions.resize(next);
  mesh.positions.shrink_to_fit();
  return true;
}

}  // namespace conelod
