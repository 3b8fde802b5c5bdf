#pragma once
// Triangles whose plane cannot be known in float: a repeated vertex, three collinear points, or
// a needle thinner than the rounding of its own vertices. Their normals would be noise (or NaN),
// and a ray that hit one would shade with it, so the loaders leave them out and say so. They
// have (next to) no area, so the picture is the mesh's without them.
#include <string>

#include "common/scene/scene_description.h"

namespace farm {

struct DegenerateTriangles {
  int repeatedVertex = 0;  // two corners at the same index or the same position
  int collinear = 0;       // distinct corners on one line: the cross product is exactly zero
  int needle = 0;          // height below kNeedleRatio of the longest edge
  int total() const { return repeatedVertex + collinear + needle; }
};

// Heights below this fraction of the longest edge are within a few float roundings of the
// vertices (2^-24 each), so the cross product that gives the normal is mostly rounding error.
constexpr double kNeedleRatio = 1e-5;

// Removes them from a triangle mesh's index list (vertices stay; they are unreferenced).
DegenerateTriangles removeDegenerateTriangles(ShapeDescription* mesh);

// "3 degenerate triangles left out (1 repeated-vertex, 1 collinear (zero-area), 1 needle)".
std::string describe(const DegenerateTriangles& d);

}  // namespace farm
