#include "common/scene/film_override.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace farm {

namespace {

constexpr double kDegrees = 180.0 / 3.14159265358979323846;

std::string sizeText(long long w, long long h) {
  return std::to_string(w) + "x" + std::to_string(h);
}

}  // namespace

double horizontalFovDegrees(const CameraDescription& camera) {
  // Mitsuba: the fov spans the image along fovAxis; the other extents follow from the aspect
  // ratio on the image plane at distance 1, where a half-extent is tan(fov / 2).
  double aspect = double(camera.width) / double(camera.height);
  double halfTan = std::tan(0.5 * camera.fovDegrees / kDegrees);
  FovAxis axis = camera.fovAxis;
  if (axis == FovAxis::Smaller) axis = aspect > 1 ? FovAxis::Y : FovAxis::X;
  if (axis == FovAxis::Larger) axis = aspect > 1 ? FovAxis::X : FovAxis::Y;
  switch (axis) {
    case FovAxis::Y:
      halfTan *= aspect;
      break;
    case FovAxis::Diagonal:
      halfTan *= aspect / std::sqrt(aspect * aspect + 1.0);
      break;
    default:
      break;
  }
  return 2.0 * std::atan(halfTan) * kDegrees;
}

void applyFilmOverride(SceneDescription& scene, int width, int height) {
  if (width < 0 || height < 0)
    throw std::invalid_argument("film override " + sizeText(width, height) +
                                ": sizes must be positive (0 keeps the scene's)");
  if (width == 0 && height == 0) return;
  CameraDescription& cam = scene.camera;
  long long w = width, h = height;
  if (w == 0) w = std::max(1LL, std::llround(double(h) * cam.width / cam.height));
  if (h == 0) h = std::max(1LL, std::llround(double(w) * cam.height / cam.width));
  constexpr long long kMaxSide = 65536, kMaxPixels = 1LL << 28;
  if (w > kMaxSide || h > kMaxSide)
    throw std::invalid_argument("film override " + sizeText(w, h) +
                                ": each side must be in [1, 65536]");
  if (w * h > kMaxPixels)
    throw std::invalid_argument("film override " + sizeText(w, h) + ": more than 2^28 pixels");
  // Only a change of aspect ratio moves the extents of axes other than the one the fov names.
  if (w * cam.height != h * cam.width && cam.fovAxis != FovAxis::X) {
    cam.fovDegrees = float(horizontalFovDegrees(cam));
    cam.fovAxis = FovAxis::X;
  }
  cam.width = int(w);
  cam.height = int(h);
}

}  // namespace farm
