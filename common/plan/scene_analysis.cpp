#include "common/plan/scene_analysis.h"

#include <algorithm>
#include <cmath>

#include "common/sampling/rng.h"
#include "common/scene/scene.h"

namespace farm {

namespace {

double shapeArea(const ShapeDescription& s) {
  if (s.type == ShapeDescription::Type::Sphere) return 4 * M_PI * double(s.radius) * s.radius;
  double area = 0;
  for (size_t t = 0; t + 2 < s.indices.size(); t += 3) {
    const Vec3f& a = s.positions[s.indices[t]];
    area +=
        0.5 *
        double(length(cross(s.positions[s.indices[t + 1]] - a, s.positions[s.indices[t + 2]] - a)));
  }
  return area;
}

// The probes see geometry through the surfaces that only bound media (null boundaries): the
// first surface along a ray that is not one, or false when the ray leaves the scene (or passes
// more boundaries than any scene nests).
constexpr int kMaxNullBoundaries = 16;
bool firstSurface(const Scene& scene, Ray ray, SurfaceHit* hit) {
  for (int k = 0; k <= kMaxNullBoundaries; ++k) {
    if (!scene.intersect(ray, hit)) return false;
    if (!scene.isNullBoundary(hit->shape)) return true;
    ray = scene.spawnRay(hit->p, hit->ng, ray.d);
  }
  return false;
}

// Whether the first surface a ray meets is specular (and -1 when it meets none).
int firstHitSpecular(const Scene& scene, const Ray& ray) {
  SurfaceHit hit;
  if (!firstSurface(scene, ray, &hit)) return -1;
  return scene.bsdfOf(hit.shape).isDelta() ? 1 : 0;
}

// Each probe sends this many rays (a seeded or fixed set: the same scene, the same plan).
constexpr int kProbeRays = 4096;

// The camera's probe rays: one through the centre of each cell of a square grid on the film.
template <typename Visit>
void forEachCameraProbe(const Scene& scene, const Visit& visit) {
  const Camera& camera = scene.camera();
  const int side = int(std::sqrt(double(kProbeRays)));
  for (int j = 0; j < side; ++j) {
    for (int i = 0; i < side; ++i) {
      visit(camera.generateRay(Vec2f((float(i) + 0.5f) / float(side) * float(camera.width()),
                                     (float(j) + 0.5f) / float(side) * float(camera.height()))));
    }
  }
}

double probeCamera(const Scene& scene) {
  int hits = 0, specular = 0;
  forEachCameraProbe(scene, [&](const Ray& ray) {
    const int s = firstHitSpecular(scene, ray);
    hits += s >= 0;
    specular += s > 0;
  });
  return hits > 0 ? double(specular) / hits : 0;
}

// The share of the light along the camera's rays that media take (scatter or absorb) before
// the first surface: the mean over the probe's rays of 1 - T, T the transmittance's luminance
// from the camera to that surface through the null boundaries on the way (exact in a
// homogeneous medium, a fine midpoint rule in a grid); and for each medium, the share of the
// rays that cross it. A ray that leaves the scene counts as clear: an open medium around the
// camera is not measured.
constexpr int kMarchSteps = 256;
double probeMediaSeen(const Scene& scene, std::vector<double>* crossedBy) {
  const size_t media = scene.description().media.size();
  crossedBy->assign(media, 0.0);
  int rays = 0;
  double taken = 0;
  std::vector<MediumSegment> segments;
  std::vector<char> crossed(media);
  forEachCameraProbe(scene, [&](const Ray& ray) {
    ++rays;
    SurfaceHit hit;
    int arrival = -1;
    if (!firstSurface(scene, ray, &hit) ||
        !scene.mediumSegments(ray.o, Vec3f(0.0f), hit.p, hit.ng, scene.cameraMedium(), &segments,
                              &arrival))
      return;
    Spectrum t(1.0f);
    std::fill(crossed.begin(), crossed.end(), 0);
    for (const MediumSegment& m : segments) {
      t = t * scene.medium(m.medium).marchedTransmittance(m.start, m.d, m.length, kMarchSteps);
      crossed[size_t(m.medium)] = 1;
    }
    taken += 1.0 - double(luminance(t));
    for (size_t k = 0; k < media; ++k) (*crossedBy)[k] += crossed[k];
  });
  for (double& c : *crossedBy) c = rays > 0 ? c / rays : 0;
  return rays > 0 ? taken / rays : 0;
}

double probeLights(const Scene& scene) {
  if (scene.lights().empty()) return 0;
  Rng rng(1, 0x9e3779b97f4a7c15ull);
  int hits = 0, specular = 0;
  for (int k = 0; k < kProbeRays; ++k) {
    float pdf = 0;
    const int light = scene.lights().pick(rng.nextFloat(), &pdf);
    const Light& l = scene.lights()[size_t(light)];
    if (l.isEnvironment()) continue;
    Vec3f p, n, w;
    if (l.isPoint()) {
      p = scene.lights().pointLight(light).position();
      w = scene.lights().pointLight(light).sampleDirection(Vec2f(rng.nextFloat(), rng.nextFloat()),
                                                           &pdf);
      n = Vec3f(0.0f);
    } else {
      const float u[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
      scene.sampleLightPoint(light, u, &p, &n);
      w = Frame(n).toWorld(
          scene.lights().sampleEmission(light, Vec2f(rng.nextFloat(), rng.nextFloat())));
    }
    if (!(pdf > 0) && l.isPoint()) continue;
    const int s = firstHitSpecular(scene, l.isPoint() ? Ray{p, w} : scene.spawnRay(p, n, w));
    hits += s >= 0;
    specular += s > 0;
  }
  return hits > 0 ? double(specular) / hits : 0;
}

// The share of camera rays whose first hit, a non-specular surface, sees a point sampled on a
// light (picked by power) that faces it: where it is small, next-event estimation from the
// camera's paths mostly finds its lights blocked and light arrives after bounces that must
// find the light by chance (a light boxed in above a plate), which bdpt's light subpaths
// carry. Environment lights are not sampled here (open scenes see their sky); with no other
// light it is 1.
double probeDirectLight(const Scene& scene) {
  Rng rng(2, 0x9e3779b97f4a7c15ull);
  int seen = 0, lit = 0;
  std::vector<MediumSegment> segments;
  forEachCameraProbe(scene, [&](const Ray& ray) {
    SurfaceHit hit;
    if (!firstSurface(scene, ray, &hit) || scene.bsdfOf(hit.shape).isDelta()) return;
    float pdf = 0;
    const int light = scene.lights().pick(rng.nextFloat(), &pdf);
    const Light& l = scene.lights()[size_t(light)];
    if (l.isEnvironment()) return;
    ++seen;
    if (scene.lightOf(hit.shape) >= 0) {
      ++lit;
      return;
    }
    Vec3f p, n(0.0f);
    if (l.isPoint()) {
      p = scene.lights().pointLight(light).position();
    } else {
      const float u[3] = {rng.nextFloat(), rng.nextFloat(), rng.nextFloat()};
      scene.sampleLightPoint(light, u, &p, &n);
      if (dot(n, hit.p - p) <= 0) return;  // the light's back: it emits from one side
    }
    int arrival = -1;
    lit += scene.hasMedia() ? scene.mediumSegments(hit.p, hit.ng, p, n, -1, &segments, &arrival)
                            : scene.visible(hit.p, hit.ng, p, n);
  });
  return seen > 0 ? double(lit) / seen : 1.0;
}

}  // namespace

const char* lightKindName(LightSummary::Kind k) {
  switch (k) {
    case LightSummary::Kind::Area:
      return "area";
    case LightSummary::Kind::Point:
      return "point";
    case LightSummary::Kind::Spot:
      return "spot";
    case LightSummary::Kind::Environment:
      return "environment";
  }
  return "?";
}

bool SceneAnalysis::specularDiffuseSpecular() const {
  // A few percent each way: a glass object on a table is seen and lit through by a sliver of
  // rays; a pool's surface covers much of both views.
  return hasSpecular() && smallLights && specularSeen >= 0.05 && specularLit >= 0.05;
}

bool SceneAnalysis::someSpecularDiffuseSpecular() const {
  return hasSpecular() && smallLights && specularSeen > 0 && specularLit > 0;
}

// Whether a mesh's vertex normals part from its faces' normals anywhere (by more than about half
// a degree): only then can the two normals disagree on a side. Many meshes carry vertex normals
// that are their flat faces' (the Cornell box's OBJ walls).
static bool isSmoothShaded(const ShapeDescription& s) {
  if (s.normals.empty() || s.faceNormals || s.normals.size() != s.positions.size()) return false;
  for (size_t t = 0; t + 2 < s.indices.size(); t += 3) {
    const Vec3f& p0 = s.positions[s.indices[t]];
    const Vec3f n = cross(s.positions[s.indices[t + 1]] - p0, s.positions[s.indices[t + 2]] - p0);
    const float len = length(n);
    if (!(len > 0)) continue;
    for (int k = 0; k < 3; ++k) {
      const Vec3f& vn = s.normals[s.indices[t + size_t(k)]];
      const float vl = length(vn);
      if (vl > 0 && std::fabs(dot(n, vn)) < 0.99995f * len * vl) return true;
    }
  }
  return false;
}

SceneAnalysis analyseScene(const Scene& scene) {
  const SceneDescription& d = scene.description();
  SceneAnalysis a;
  for (size_t i = 0; i < d.shapes.size(); ++i) {
    const ShapeDescription& s = d.shapes[i];
    if (s.bsdf < 0 || s.nullBoundary) continue;
    const BsdfDescription& b = d.bsdfs[size_t(s.bsdf)];
    const double area = shapeArea(s);
    using T = BsdfDescription::Type;
    if (scene.bsdfOf(int(i)).isDelta()) {
      ++a.specularShapes;
      a.specularArea += area;
      a.facetedSpecularShapes += !scene.smoothSpecularShape(int(i));
    } else if (b.type != T::Diffuse && b.alpha <= kGlossyAlpha) {
      ++a.glossyShapes;
      a.glossyArea += area;
    } else {
      ++a.diffuseShapes;
      a.diffuseArea += area;
    }
  }
  for (const BsdfDescription& b : d.bsdfs) a.texturedBsdfs += b.reflectanceTexture >= 0;
  for (const ShapeDescription& s : d.shapes) a.smoothShapes += isSmoothShaded(s);
  a.strictNormals = scene.strictNormals();

  const double diameter = 2.0 * double(scene.extent());
  double total = 0;
  a.smallLights = true;
  for (size_t k = 0; k < scene.lights().size(); ++k) {
    const Light& l = scene.lights()[k];
    LightSummary s;
    s.power = double(l.power);
    total += s.power;
    if (l.isEnvironment()) {
      s.kind = LightSummary::Kind::Environment;
      s.origin = d.environment.origin;
      a.smallLights = false;
    } else if (l.isPoint()) {
      const PointLightDescription& p = d.pointLights[size_t(l.point)];
      s.kind = p.spot ? LightSummary::Kind::Spot : LightSummary::Kind::Point;
      s.origin = p.origin;
    } else {
      s.kind = LightSummary::Kind::Area;
      s.origin = d.shapes[size_t(l.shape)].origin;
      s.area = double(l.area);
      s.size = std::sqrt(s.area) / diameter;
      a.smallLights = a.smallLights && s.size < kSmallLight;
    }
    a.lights.push_back(s);
  }
  if (a.lights.empty()) a.smallLights = false;
  for (LightSummary& s : a.lights) s.share = total > 0 ? s.power / total : 0;

  a.lensRadius = d.camera.lensRadius;
  a.thinLens = d.camera.lensRadius > 0;
  a.environment = d.environment.present;
  a.environmentMap = d.environment.present && d.environment.image != nullptr;
  for (const MediumDescription& m : d.media) {
    if (m.type == MediumDescription::Type::Grid) {
      ++a.gridMedia;
    } else {
      ++a.homogeneousMedia;
    }
  }
  if (a.hasMedia()) {
    std::vector<double> crossedBy;
    a.mediaSeen = probeMediaSeen(scene, &crossedBy);
    for (size_t k = 0; k < d.media.size(); ++k) {
      if (crossedBy[k] > 0)
        a.mediaLookedThrough.push_back(
            {d.media[k].id.empty() ? d.media[k].origin : d.media[k].id, crossedBy[k]});
    }
  }
  a.maxDepth = d.maxDepth;
  if (!scene.lights().empty()) a.directlyLit = probeDirectLight(scene);
  if (a.hasSpecular()) {
    a.specularSeen = probeCamera(scene);
    a.specularLit = probeLights(scene);
    a.probeRays = 2 * kProbeRays;
  }
  for (Algorithm algorithm : allAlgorithms()) {
    std::string why = algorithmRefusal(d, algorithm);
    if (why.empty()) {
      a.usable.push_back(algorithm);
    } else {
      a.refused.emplace_back(algorithm, std::move(why));
    }
  }
  return a;
}

std::string algorithmRefusal(const SceneDescription& desc, Algorithm algorithm) {
  const bool pathSpace = algorithm == Algorithm::MLT || algorithm == Algorithm::ERPT;
  const std::string name = algorithmName(algorithm);
  // Path-space chains end camera subpaths on the environment where their rays leave the scene
  // and connect to it along its direction; through media that would need each such edge's
  // transmittance to infinity in their densities and moves, which they do not have yet.
  if (pathSpace && desc.environment.present && !desc.media.empty()) {
    return "an environment light in a scene with media is not supported by " + name +
           " yet (its mutations end paths on the environment only in vacuum): use pt, bdpt, "
           "pssmlt, pssmlt-pt or mmlt";
  }
  return "";
}

}  // namespace farm
