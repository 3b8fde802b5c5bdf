#pragma once
// What a scene file says, resolved and in world space: the loaders' output and the only input of
// Scene (the renderer's ray-traceable form). Shapes are triangle meshes except spheres, which stay
// analytic. Plain data: no Embree, no file handles.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/math/transform.h"
#include "common/math/vec.h"
#include "common/scene/texture.h"

namespace farm {

enum class FovAxis { X, Y, Smaller, Larger, Diagonal };
// Box: one pixel; Tent: radius one pixel; Gaussian: exp(-alpha d^2) - exp(-alpha r^2) per axis
// within radius r (pbrt's and Mitsuba's truncated gaussian).
enum class FilterType { Box, Tent, Gaussian };

struct CameraDescription {
  // Camera-to-world. Camera space as Mitsuba's perspective sensor: looks down +z, +y up,
  // +x towards the image's left.
  Matrix4 toWorld = Matrix4::identity();
  float fovDegrees = 45.0f;
  FovAxis fovAxis = FovAxis::X;
  int width = 768, height = 576;  // film size in pixels
  FilterType filter = FilterType::Tent;
  float filterRadius = 2, filterAlpha = 2;  // Gaussian only, in pixels
  // Thin lens (Mitsuba's thinlens, pbrt's lensradius): a lens disk of this radius, focused at
  // this distance along the view direction; 0: a pinhole.
  float lensRadius = 0;
  float focusDistance = 1;
};

enum class MicrofacetDistribution { Beckmann, GGX };
class CoatingTransmittance;  // bsdf.h

struct BsdfDescription {
  // Mitsuba 0.6's diffuse, dielectric (smooth), conductor (smooth), roughconductor and
  // roughdielectric; pbrt's plastic: a diffuse lobe (reflectance) plus a microfacet reflection
  // lobe (specularReflectance, alpha) with the Fresnel term of a dielectric of index intIOR.
  // CoatedDiffuse: Mitsuba's roughplastic (and plastic, and pbrt-v4's coateddiffuse, as a coat
  // of tiny roughness where they are smooth): the same glossy lobe over a Lambertian base seen
  // through the coat, whose light the coat's rough transmittance lets in and out (`coating`).
  enum class Type {
    Diffuse,
    Dielectric,
    Conductor,
    RoughConductor,
    RoughDielectric,
    Plastic,
    CoatedDiffuse
  };
  Type type = Type::Diffuse;
  std::string id;         // the XML id, or empty
  bool twoSided = false;  // wrapped in Mitsuba's "twosided"
  // diffuse: the reflectance, or where reflectanceTexture >= 0 the texture
  // SceneDescription::textures[reflectanceTexture] gives it
  Spectrum reflectance{0.5f};
  int reflectanceTexture = -1;
  // dielectric and roughdielectric: interior and exterior indices of refraction
  float intIOR = 1.5046f, extIOR = 1.000277f;
  // roughconductor, roughdielectric and plastic
  MicrofacetDistribution distribution = MicrofacetDistribution::Beckmann;
  float alpha = 0.1f;
  // conductor and roughconductor
  Spectrum eta{0.0f}, k{1.0f};  // complex index of refraction of the conductor
  float extEta = 1.0f;          // index of the exterior medium
  Spectrum specularReflectance{1.0f};
  // CoatedDiffuse: the coat's transmittance for (distribution, alpha, intIOR / extIOR), made by
  // makeCoatingTransmittance (bsdf.h); and Mitsuba's "nonlinear" (the base's inter-reflections
  // under the coat darken and saturate its colour: rho / (1 - rho Fdr) instead of rho /
  // (1 - Fdr)).
  std::shared_ptr<const CoatingTransmittance> coating;
  bool nonlinear = false;
};

struct ShapeDescription {
  enum class Type { TriangleMesh, Sphere };
  Type type = Type::TriangleMesh;
  // TriangleMesh, world space
  std::vector<Vec3f> positions;
  std::vector<Vec3f> normals;     // per vertex, may be empty (then geometric normals are used)
  std::vector<Vec2f> uvs;         // per vertex texture coordinates, may be empty (then (0, 0))
  std::vector<uint32_t> indices;  // 3 per triangle
  bool faceNormals = false;       // ignore vertex normals
  // Sphere, world space
  Vec3f center;
  float radius = 1.0f;
  bool flipNormals = false;
  // Material and emission
  int bsdf = -1;  // index into SceneDescription::bsdfs
  bool isEmitter = false;
  Spectrum radiance{0.0f};      // area emitter radiance (emits on the side the normal faces)
  bool emitsBothSides = false;  // pbrt's "twosided" area light: the same radiance on both
  // Where it came from, for messages
  std::string origin;  // e.g. "scene.xml:42 (obj models/Mesh001.obj)"
};

// Light from infinitely far away (Mitsuba's constant and envmap, pbrt's infinite): the radiance
// arriving from world direction w (pointing away from the scene) is scale times the image at
// w's direction in the light's frame, or scale alone without an image. The frame is pbrt's:
// local z up. A lat-long image has u = phi / 2 pi with phi = atan2(y, x), v = theta / pi from
// its top row; an equal-area one (pbrt-v4's, square) is Clarberg's octahedral map (warp.h's
// equalAreaSphereToSquare), v from its top row too. toWorld takes the frame to world space (the
// Mitsuba loader folds its own y-up convention in).
struct EnvironmentDescription {
  enum class Mapping { LatLong, EqualArea };
  bool present = false;
  Spectrum scale{1.0f};
  std::shared_ptr<const TextureImage> image;  // the map, or null for a constant
  Mapping mapping = Mapping::LatLong;
  Matrix4 toWorld = Matrix4::identity();  // a rotation
  std::string origin;                     // "scene.xml:12 (envmap sky.exr)", for messages
};

// A point light (pbrt's point and spot, Mitsuba's point and spot): radiant intensity
// `intensity` (power per unit solid angle) from `position`. A spot emits only within
// cosTotalWidth of `direction`: fully inside cosFalloffStart, falling off between as its format
// says. Point lights are invisible: a path meets one only by being connected to it.
struct PointLightDescription {
  Vec3f position;
  Spectrum intensity{1.0f};
  bool spot = false;
  Vec3f direction{0, 0, 1};  // unit; spots only
  float cosTotalWidth = -1, cosFalloffStart = -1;
  // pbrt-v3: ((cos - cosTotal) / (cosStart - cosTotal))^4; pbrt-v4: smoothstep of the same;
  // Mitsuba: linear in the angle between the beam width and the cutoff.
  enum class Falloff { PbrtV3Quartic, PbrtV4Smoothstep, MitsubaLinearAngle };
  Falloff falloff = Falloff::PbrtV3Quartic;
  std::string origin;  // "scene.pbrt:12 (spot)", for messages
};

struct SceneDescription {
  std::string sourcePath;
  CameraDescription camera;
  int maxDepth = -1;  // longest path in edges, Mitsuba's convention; -1 = unbounded
  std::vector<BsdfDescription> bsdfs;
  std::vector<TextureDescription> textures;
  std::vector<ShapeDescription> shapes;
  EnvironmentDescription environment;
  std::vector<PointLightDescription> pointLights;
  // What the loader changed or left out, one line each ("FILE:LINE: ..."), for the user.
  std::vector<std::string> warnings;
};

}  // namespace farm
