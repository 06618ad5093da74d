// ConeLOD tests — tiny meshes built in code, and the path of the real meshes.
#pragma once

#include <cmath>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>

#include "conelod/mesh/indexed_mesh.h"

namespace conelod {
namespace test {

// ../shared/test_meshes from the repository root (set by CMake; overridable by the environment).
inline std::string MeshPath(const std::string& name) {
  const char* env = std::getenv("CONELOD_TEST_MESHES");
  return std::string(env ? env : CONELOD_TEST_MESHES) + "/" + name;
}

// An axis-aligned unit cube: 8 vertices, 12 triangles (two per side), outward normals.
inline IndexedMesh Cube() {
  IndexedMesh m;
  for (int i = 0; i < 8; ++i) m.positions.emplace_back(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
  // Each side as a quad (a,b,c,d) counter-clockwise seen from outside.
  const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.faces.push_back({q[0], q[1], q[2]});
    m.faces.push_back({q[0], q[2], q[3]});
  }
  return m;
}

// A sphere of radius 1: an octahedron subdivided `levels` times, vertices projected.
inline IndexedMesh Sphere(int levels) {
  IndexedMesh m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      vcg::Point3f p = (m.positions[a] + m.positions[b]) * 0.5f;
      p.Normalize();
      m.positions.push_back(p);
      return mid[key] = uint32_t(m.positions.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> next;
    for (const auto& t : m.faces) {
      const uint32_t ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({ab, t[1], bc});
      next.push_back({ca, bc, t[2]});
      next.push_back({ab, bc, ca});
    }
    m.faces.swap(next);
  }
  return m;
}

// A thin closed lens: two n x n grids over the unit square, bulging by +-h at the centre and
// sharing their rim (the two layers meet back to back there, as a scan's layers where a crack was
// welded, or a blade's two sides).
inline IndexedMesh Lens(int n, float h) {
  IndexedMesh m;
  auto id = [n](int layer, int x, int y) -> uint32_t {
    const bool rim = x == 0 || y == 0 || x == n || y == n;
    return uint32_t((rim ? 0 : layer) * (n + 1) * (n + 1) + y * (n + 1) + x);
  };
  for (int layer = 0; layer < 2; ++layer)
    for (int y = 0; y <= n; ++y)
      for (int x = 0; x <= n; ++x) {
        const float u = float(x) / n, v = float(y) / n;
        const float z = (layer ? -h : h) * 16 * u * (1 - u) * v * (1 - v);
        m.positions.emplace_back(u, v, z);
      }
  for (int layer = 0; layer < 2; ++layer)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        uint32_t a = id(layer, x, y), b = id(layer, x + 1, y), c = id(layer, x + 1, y + 1), d = id(layer, x, y + 1);
        if (layer) std::swap(b, d);  // the lower layer faces down
        m.faces.push_back({a, b, c});
        m.faces.push_back({a, c, d});
      }
  return m;
}

// An n x n grid of quads (2 triangles each) in the z = 0 plane, normals +z.
inline IndexedMesh Grid(int n) {
  IndexedMesh m;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) m.positions.emplace_back(float(x), float(y), 0.f);
  auto id = [n](int x, int y) { return uint32_t(y * (n + 1) + x); };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      m.faces.push_back({id(x, y), id(x + 1, y), id(x + 1, y + 1)});
      m.faces.push_back({id(x, y), id(x + 1, y + 1), id(x, y + 1)});
    }
  return m;
}

}  // namespace test
}  // namespace conelod
