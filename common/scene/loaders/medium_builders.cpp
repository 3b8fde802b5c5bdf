#include "common/scene/loaders/medium_builders.h"

namespace farm {

void setScattering(MediumDescription* m, const Spectrum& sigmaA, const Spectrum& sigmaS,
                   double scale) {
  m->sigmaA = sigmaA * float(scale);
  m->sigmaS = sigmaS * float(scale);
}

void setExtinction(MediumDescription* m, const Spectrum& sigmaT, const Spectrum& albedo,
                   double scale) {
  const Spectrum sigmaS = sigmaT * albedo;
  setScattering(m, sigmaT - sigmaS, sigmaS, scale);
}

}  // namespace farm
