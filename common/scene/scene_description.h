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
  int medium = -1;  // index into SceneDescription::media the camera sits in; -1: vacuum
};

enum class MicrofacetDistribution { Beckmann, GGX };
class CoatingTransmittance;  // bsdfs/coating_transmittance.h

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
  // sharedCoatingTransmittance (bsdfs/coating_transmittance.h); and Mitsuba's "nonlinear" (the
  // base's inter-reflections under the coat darken and saturate its colour: rho / (1 - rho Fdr)
  // instead of rho / (1 - Fdr)).
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
  // Participating media on either side of the surface (indices into SceneDescription::media,
  // -1 for vacuum), the interior on the side opposite the normal. With neither set the surface
  // leaves a ray's medium as it is (pbrt's rule); nullBoundary: the surface does not scatter at
  // all and only marks where one medium ends and the other begins (Mitsuba's shape with a
  // medium and no BSDF, pbrt's "interface" material).
  bool hasMediumInterface = false;
  int interiorMedium = -1, exteriorMedium = -1;
  bool nullBoundary = false;
  // Where it came from, for messages
  std::string origin;  // e.g. "scene.xml:42 (obj models/Mesh001.obj)"
};

// A participating medium: extinction sigma_t = sigma_a + sigma_s (per unit of world length),
// scattering by the Henyey-Greenstein phase function of mean cosine g. Homogeneous: sigmaA and
// sigmaS everywhere. Grid: sigmaA and sigmaS times a density that a grid of nx * ny * nz values
// (x fastest) gives by trilinear interpolation over the unit cube of the grid's own space
// (worldToGrid takes world points there; the density is 0 outside). Values at cell centres
// (pbrt-v3: sample i at (i + 0.5) / n) or at cell corners (Mitsuba's gridvolume: sample i at
// i / (n - 1)). A grid's sigma_t must be grey (equal in every channel: distances are sampled
// by delta tracking against one majorant, as Mitsuba's heterogeneous medium does); its albedo
// may have colour.
struct MediumDescription {
  enum class Type { Homogeneous, Grid };
  Type type = Type::Homogeneous;
  Spectrum sigmaA{0.0f}, sigmaS{0.0f};
  float g = 0;  // in (-1, 1)
  int nx = 0, ny = 0, nz = 0;
  std::vector<float> density;
  bool cellCentred = true;
  Matrix4 worldToGrid = Matrix4::identity();
  std::string id;      // the file's name for it, or empty
  std::string origin;  // "scene.xml:12 (homogeneous)", for messages
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
  // Mitsuba's strictNormals (Scene::sidesAgree): paths whose directions the geometric and the
  // shading normal put on different sides of a surface are dropped. Mitsuba files say so in their
  // integrator (Mitsuba's default there is false); pbrt files have no such switch and keep this
  // default; `--shading-normals` overrides either (RenderSettings::shadingNormals).
  bool strictNormals = true;
  std::vector<BsdfDescription> bsdfs;
  std::vector<TextureDescription> textures;
  std::vector<ShapeDescription> shapes;
  EnvironmentDescription environment;
  std::vector<PointLightDescription> pointLights;
  std::vector<MediumDescription> media;
  // What the loader changed or left out, one line each ("FILE:LINE: ..."), for the user.
  std::vector<std::string> warnings;
};

}  // namespace farm
