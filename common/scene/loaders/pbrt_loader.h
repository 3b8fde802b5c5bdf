#pragma once
// pbrt-v3 and pbrt-v4 scene files (the common subset of published scenes) to a
// SceneDescription in world space.
//
// Supported: Camera "perspective" (fov, lensradius, focaldistance), Film (resolution), PixelFilter
// box of radius 0.5, triangle of radius 1 and gaussian (v4's default filter for v4 files),
// Integrator maxdepth (of any unbiased integrator: the farm picks the algorithm), Sampler and
// Accelerator (ignored); Transform, ConcatTransform, Translate, Rotate, Scale, LookAt, Identity,
// CoordinateSystem, CoordSysTransform, TransformBegin/End, AttributeBegin/End, ReverseOrientation;
// Include and Import; Material, MakeNamedMaterial, NamedMaterial with matte/diffuse,
// metal/conductor (rgb or named metal spectra), mirror, glass/dielectric, rough variants with
// remaproughness (v3's polynomial, v4's square root, told by the material's name), v3's plastic,
// v4's coateddiffuse (non-scattering coat);
// Texture imagemap, checkerboard, scale and constant with uv mapping; Shape trianglemesh, plymesh,
// sphere, disk (tessellated) and planar bilinear patches; ObjectBegin/End and ObjectInstance
// (flattened: each instance copies its object's shapes); AreaLightSource diffuse (one- or
// two-sided); LightSource infinite (constant, a lat-long map, or v4's equal-area one), point and
// spot.
//
// Everything else that would change the picture is an error naming file, line and what is not
// supported. Meshes, textures and included files must be inside the scene's folder.
#include <string>

#include "common/scene/loaders/scene_files.h"
#include "common/scene/scene_description.h"

namespace farm {

// Throws SceneLoadError for anything it cannot load faithfully.
SceneDescription loadPbrtScene(const std::string& path);

}  // namespace farm
