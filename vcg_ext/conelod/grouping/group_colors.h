// ConeLOD — distinct display colours for group ids.
//
// Hues follow the golden-ratio sequence so that consecutive ids (often neighbours on the mesh)
// get far-apart hues; saturation and value alternate a little for more distinct neighbours.
#pragma once

#include <cmath>

#include <vcg/space/color4.h>

namespace conelod {

inline vcg::Color4b GroupColor(int id) {
  const double h = std::fmod(0.13 + 0.6180339887498949 * id, 1.0) * 6.0;
  const double s = (id % 3 == 0) ? 0.55 : (id % 3 == 1 ? 0.75 : 0.95);
  const double v = (id % 2 == 0) ? 0.95 : 0.78;
  const int i = int(h);
  const double f = h - i, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  double r, g, b;
  switch (i % 6) {
    case 0:
      r = v;
      g = t;
      b = p;
      break;
    case 1:
      r = q;
      g = v;
      b = p;
      break;
    case 2:
      r = p;
      g = v;
      b = t;
      break;
    case 3:
      r = p;
      g = q;
      b = v;
      break;
    case 4:
      r = t;
      g = p;
      b = v;
      break;
    default:
      r = v;
      g = p;
      b = q;
      break;
  }
  return vcg::Color4b((unsigned char)(r * 255 + 0.5), (unsigned char)(g * 255 + 0.5), (unsigned char)(b * 255 + 0.5),
                      255);
}

}  // namespace conelod
