#pragma once
// The camera and film a scene file may name, set here from physical values, so that the two
// loaders only read their own names and spell their own errors. What each format's names mean,
// side by side (a loader's parameters in brackets; common/scene/camera.h makes the rays):
//
// | | Mitsuba 0.6 | pbrt-v3 | pbrt-v4 |
// |---|---|---|---|
// | pinhole | sensor "perspective" (fov across fovAxis: x, y, smaller, larger or diagonal; or
// focalLength, a 35 mm film's, across the diagonal; toWorld, +x to the image's left) | Camera
// "perspective" (fov across the shorter side; the transformation in force is world to camera, +x to
// the image's right) | the same | | thin lens | sensor "thinlens" (apertureRadius, focusDistance,
// in world units) | "perspective" (lensradius, focaldistance, in camera space) | the same | | film
// | film (width, height; 768 x 576) | Film "image" (xresolution, yresolution; 1280 x 720) | also
// "rgb", "gbuffer" | | pixel filter | rfilter "box", "tent", "gaussian" (stddev 0.5, cut off at 4
// stddev) | PixelFilter "box" (radius 0.5), "triangle" (radius 1), "gaussian" (xwidth 2, alpha 2) |
// the same, "gaussian" (xradius 1.5, sigma 0.5) |
//
// Neither format's camera medium is here: it is where the camera sits (medium_builders.h).
#include "common/scene/scene_description.h"

namespace farm {

// The largest film either loader takes: a side, and the pixels.
constexpr long long kMaxFilmSide = 65536;
constexpr long long kMaxFilmPixels = 1LL << 28;

// A gaussian pixel filter exp(-alpha x^2), less its value at `radius`, where it is cut off
// (pixels): pbrt's alpha, or 1 / (2 sigma^2); Mitsuba's 1 / (2 stddev^2) and radius 4 stddev.
void setGaussianFilter(CameraDescription* camera, double radius, double alpha);

}  // namespace farm
