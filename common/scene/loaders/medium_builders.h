#pragma once
// The participating media a scene file may name, their coefficients set here from physical
// values, so that the two loaders only read their own names and spell their own errors. What
// each format's names mean, side by side (a loader's parameters in brackets; common/scene/medium.h
// holds their sampling and mediumProblem their checks):
//
// | medium | Mitsuba 0.6 | pbrt-v3 | pbrt-v4 |
// |---|---|---|---|
// | homogeneous | medium "homogeneous" (sigmaA and sigmaS, or sigmaT and albedo; scale or
// densityMultiplier) | MakeNamedMedium "homogeneous" (sigma_a, sigma_s, scale) | the same | | a
// grid of densities | medium "heterogeneous" (a volume "density": a gridvolume's .vol file or, the
// farm's extension, an OpenVDB one; a constant volume "albedo"; scale) | "heterogeneous" (nx, ny,
// nz, density, p0, p1; sigma_a, sigma_s, scale) | "uniformgrid" (the same), "nanovdb" (filename: an
// OpenVDB file here) | | its phase function | a nested phase "isotropic" or "hg" (g) | g | g | |
// where it is | a shape's medium or ref named interior or exterior; a sensor's | MediumInterface
// (inside, outside), for shapes and the camera alike | the same |
//
// In a grid sigma_a and sigma_s are those of a density of 1: Mitsuba's sigma_t is scale times
// the density and its albedo constant, pbrt's coefficients are scaled by the density.
#include "common/scene/scene_description.h"

namespace farm {

// Sets m's sigma_a and sigma_s to sigmaA and sigmaS times scale.
void setScattering(MediumDescription* m, const Spectrum& sigmaA, const Spectrum& sigmaS,
                   double scale);

// Sets them from an extinction sigmaT and a single-scattering albedo, both times scale:
// sigma_s = albedo sigma_t, sigma_a = sigma_t - sigma_s.
void setExtinction(MediumDescription* m, const Spectrum& sigmaT, const Spectrum& albedo,
                   double scale);

}  // namespace farm
