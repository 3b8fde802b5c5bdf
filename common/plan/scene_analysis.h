#pragma once
// What a scene has that decides how to render it (docs/design.md, "Leave out what a scene does not
// need"): its surfaces by kind, its lights and their sizes and powers, its camera, textures,
// environment and media, and probes: where specular surfaces sit on the light's way (the share
// of camera rays whose first hit is specular, and the share of light rays whose first hit is),
// how much of what the camera sees sees a light, and how much light media take from the
// camera's rays. render_plan.h turns this into a plan.
#include <string>
#include <utility>
#include <vector>

#include "common/chain/algorithm.h"

namespace farm {

class Scene;
struct SceneDescription;

// A glossy lobe this narrow (microfacet alpha at most this) makes paths through it nearly as
// hard to connect as a specular one's; wider ones are treated as rough.
constexpr float kGlossyAlpha = 0.3f;
// A light whose side (the square root of its area) is below this share of the scene's diameter
// is small: BDPT's connections to it are fine, but paths that must hit it by chance (through a
// specular chain) are rare.
constexpr double kSmallLight = 0.1;

struct LightSummary {
  enum class Kind { Area, Point, Spot, Environment };
  Kind kind = Kind::Area;
  std::string origin;  // the file and line, or the shape's origin
  double area = 0;     // area lights
  double size = 0;     // sqrt(area) over the scene's diameter; 0 for points and spots
  double power = 0;    // luminance of the emitted power (the light selection weight)
  double share = 0;    // of all lights' power
};
const char* lightKindName(LightSummary::Kind k);

struct SceneAnalysis {
  // Shapes by their BSDF (emitters without a BSDF are not counted): specular (Dirac lobes
  // only: smooth dielectric and conductor), glossy (microfacet lobes of alpha <= kGlossyAlpha),
  // diffuse (Lambertian, or rougher lobes).
  int specularShapes = 0, glossyShapes = 0, diffuseShapes = 0;
  // Specular shapes that are faceted (Scene::smoothSpecularShape false): flat-shaded and curved.
  int facetedSpecularShapes = 0;
  double specularArea = 0, glossyArea = 0, diffuseArea = 0;
  std::vector<LightSummary> lights;
  bool smallLights = false;  // every light is small (kSmallLight) or a point
  bool thinLens = false;
  float lensRadius = 0;
  int texturedBsdfs = 0;  // BSDFs whose reflectance a texture gives
  // Shapes shaded by interpolated vertex normals, and the convention the scene renders them
  // with (Scene::sidesAgree): strict normals drop the paths whose directions a shape's two
  // normals put on different sides of it.
  int smoothShapes = 0;
  bool strictNormals = true;
  bool environment = false, environmentMap = false;
  int homogeneousMedia = 0, gridMedia = 0;
  int maxDepth = -1;
  // Probes (a fixed, seeded set of rays): the share of camera rays through the film whose first
  // hit is a specular surface, and of rays leaving the lights (by power) whose first hit is.
  // Both look through the surfaces that only bound media (a glass ball in a fog-filled box is
  // seen and lit through the box's faces).
  double specularSeen = 0, specularLit = 0;
  int probeRays = 0;
  // The share of the light along camera rays that media take (scatter or absorb) before the
  // first surface (scene_analysis.cpp: probeMediaSeen): 0 in vacuum, and about 0 in a medium
  // too thin to matter.
  double mediaSeen = 0;
  // The media the camera looks through: each one's name (its id, or where the file gives it)
  // and the share of camera rays that cross it before their first surface.
  std::vector<std::pair<std::string, double>> mediaLookedThrough;
  // The share of camera rays whose first (non-specular) hit sees a point sampled on a light
  // (scene_analysis.cpp: probeDirectLight); 1 with no finite light.
  double directlyLit = 1;
  // The algorithms that can render it, and for each of the others why not (algorithmRefusal).
  std::vector<Algorithm> usable;
  std::vector<std::pair<Algorithm, std::string>> refused;

  bool hasSpecular() const { return specularShapes > 0; }
  bool hasMedia() const { return homogeneousMedia + gridMedia > 0; }
  // Light reaches the camera along L S+ D S+ E paths that no local sampler connects: the camera
  // sees diffuse surfaces through specular ones, and small lights light them through specular
  // ones (the water caustic). Only the manifold walks of path-space MLT find these.
  bool specularDiffuseSpecular() const;
  // Some light, perhaps little, comes along such paths: the camera sees a specular surface and
  // small lights light one, both at all (veach-bidir's glass egg under its lamp: 1% and 0.7%).
  // pt and bdpt reach it only by hitting a light, in rare bright samples; a Markov chain that
  // finds such a path holds it. Implied by specularDiffuseSpecular().
  bool someSpecularDiffuseSpecular() const;
};

SceneAnalysis analyseScene(const Scene& scene);

// Why `algorithm` cannot render a scene with this description, for the user (one line), or
// empty when it can: path-space MLT and ERPT build paths from lights at finite points only;
// ERPT's chains cannot start from path tracing's estimate of a grid's transmittance.
std::string algorithmRefusal(const SceneDescription& desc, Algorithm algorithm);

}  // namespace farm
