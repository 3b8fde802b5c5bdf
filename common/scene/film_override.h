#pragma once
// Rendering a scene at another resolution than its file says (previews, tests, references) without
// changing what the camera sees.
#include "common/scene/scene_description.h"

namespace farm {

// Sets the film to width x height. 0 keeps a dimension; when only one is given, the other follows
// the scene's aspect ratio (rounded, at least 1). The horizontal field of view is kept: a fov given
// for another axis (y, smaller, larger, diagonal) is first converted to the x-axis fov of the
// original film when the aspect ratio changes. Throws std::invalid_argument for negative sizes or
// a film outside the loaders' bounds ([1, 65536] a side, at most 2^28 pixels).
void applyFilmOverride(SceneDescription& scene, int width, int height);

// The horizontal (x-axis) field of view, in degrees, that `camera` has on its own film.
double horizontalFovDegrees(const CameraDescription& camera);

}  // namespace farm
