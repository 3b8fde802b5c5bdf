#include "common/scene/loaders/camera_builders.h"

namespace farm {

void setGaussianFilter(CameraDescription* camera, double radius, double alpha) {
  camera->filter = FilterType::Gaussian;
  camera->filterRadius = float(radius);
  camera->filterAlpha = float(alpha);
}

}  // namespace farm
