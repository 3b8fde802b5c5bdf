#pragma once
// The lights a scene file may name, made here from physical values, so that the two loaders only
// read their own names and spell their own errors. What each format's names mean, side by side
// (a loader's parameters in brackets; common/scene/lights.h owns picking and sampling them):
//
// | light | Mitsuba 0.6 | pbrt-v3 | pbrt-v4 |
// |---|---|---|---|
// | area (ShapeDescription::radiance) | emitter "area" nested in a shape (radiance) |
// AreaLightSource "diffuse" (L, scale, twosided) | the same | | point (pointLight) | emitter
// "point" (intensity; position, or toWorld's origin) | LightSource "point" (I, scale, from) | the
// same | | spot (aimSpot) | emitter "spot" (intensity; toWorld's origin and +z; cutoffAngle,
// beamWidth; linear in the angle) | LightSource "spot" (I, scale, from, to, coneangle,
// conedeltaangle; quartic) | (conedelta; smoothstep) | | environment (makeEnvironment) | emitter
// "constant" (radiance), "envmap" (filename, lat-long with y up; scale, toWorld) | LightSource
// "infinite" (L, scale; mapname, lat-long with z up) | (filename: square equal-area or lat-long) |
#include <filesystem>
#include <string>

#include "common/math/transform.h"
#include "common/scene/scene_description.h"

namespace farm {

// A point light of radiant intensity `intensity` at `position`, `origin` naming it in messages
// ("scene.pbrt:12 (point)").
PointLightDescription pointLight(const Vec3f& position, const Spectrum& intensity,
                                 const std::string& origin);

// Makes *light a spot aimed along `axis` (world space, finite and non-zero): dark beyond
// totalDegrees from it, fully bright within falloffStartDegrees (0 <= start <= total), falling
// off between as `falloff` says.
void aimSpot(PointLightDescription* light, const Vec3f& axis, double totalDegrees,
             double falloffStartDegrees, PointLightDescription::Falloff falloff);

// An environment light as both loaders describe it (see EnvironmentDescription): `lightToWorld`
// in pbrt's frame (z up) must be a rotation, possibly mirrored and uniformly scaled; `filename`
// (in the scene's folder `dir`; empty for a constant) a lat-long map, twice as wide as high, or
// where equalAreaAllowed (pbrt-v4's "filename") a square equal-area one. Errors are
// SceneLoadErrors at file:line.
EnvironmentDescription makeEnvironment(const std::filesystem::path& dir, const std::string& file,
                                       int line, const Spectrum& scale, const Matrix4& lightToWorld,
                                       const std::string& filename, bool equalAreaAllowed);

}  // namespace farm
