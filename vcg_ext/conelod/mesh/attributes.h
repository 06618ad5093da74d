// ConeLOD — the per-vertex attributes a scan carries (colour, normals, texture coordinates) as
// float channels, the layout the attribute-carrying collapse (attribute_quadric.h) and the
// adapters share.
#pragma once

#include <cstddef>
#include <vector>

namespace conelod {

// Attributes as float channels: colour (RGB or RGBA in [0, 1]), then normal (3), then texture
// coordinates (2), each only when present. values: one record of channels() floats per vertex
// (or per face corner, where the user says so).
struct VertexAttributes {
  int colorChannels = 0;  // 0, 3 or 4
  bool normals = false;
  bool texCoords = false;
  std::vector<float> values;

  int channels() const { return colorChannels + (normals ? 3 : 0) + (texCoords ? 2 : 0); }
  int normalOffset() const { return colorChannels; }
  int texCoordOffset() const { return colorChannels + (normals ? 3 : 0); }
  bool empty() const { return channels() == 0; }
  const float* of(size_t v) const { return values.data() + v * size_t(channels()); }
  float* of(size_t v) { return values.data() + v * size_t(channels()); }
};

}  // namespace conelod
