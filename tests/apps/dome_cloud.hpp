#pragma once
// The scanned dome the drom copy tests copy: a hemisphere of radius 15 on z = 0 sampled on rings 1 mm
// apart, with exact normals, as ASCII PLY; `extra` vertex lines (x y z nx ny nz) after them.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

inline std::string dome_ply(const std::vector<std::string>& extra = {}) {
  std::ostringstream body;
  int n = 0;
  for (int i = 0; i <= 23; ++i) {
    const double polar = M_PI / 2 * i / 23, r = 15 * std::sin(polar);
    const int around = std::max(1, static_cast<int>(std::ceil(2 * M_PI * r)));
    for (int k = 0; k < around; ++k, ++n) {
      const double phi = 2 * M_PI * k / around;
      const double nx = std::sin(polar) * std::cos(phi), ny = std::sin(polar) * std::sin(phi), nz = std::cos(polar);
      body << 15 * nx << " " << 15 * ny << " " << 15 * nz << " " << nx << " " << ny << " " << nz << "\n";
    }
  }
  for (const auto& line : extra) body << line << "\n", ++n;
  return "ply\nformat ascii 1.0\nelement vertex " + std::to_string(n) +
         "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n" + body.str();
}

// How many of the dome's points lie beyond `polar` degrees from its top.
inline int dome_points_past(double polar_degrees) {
  int n = 0;
  for (int i = 0; i <= 23; ++i) {
    const double polar = M_PI / 2 * i / 23, r = 15 * std::sin(polar);
    if (polar * 180 / M_PI > polar_degrees) n += std::max(1, static_cast<int>(std::ceil(2 * M_PI * r)));
  }
  return n;
}
