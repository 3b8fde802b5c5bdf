#pragma once
// Scenes the statistical tests write for themselves (test code only): the white furnace, with
// its analytic answers, a glass ball for the specular paths, and a sky for environment lights.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>

#include "common/sampling/warp.h"
#include "common/scene/scene_description.h"

namespace farm {

// A parallelogram of two triangles from `corner` along two edges, its normal edge1 x edge2.
inline ShapeDescription quadShape(const Vec3f& corner, const Vec3f& edge1, const Vec3f& edge2,
                                  int bsdf) {
  ShapeDescription s;
  s.positions = {corner, corner + edge1, corner + edge1 + edge2, corner + edge2};
  s.indices = {0, 1, 2, 0, 2, 3};
  s.bsdf = bsdf;
  return s;
}

inline ShapeDescription sphereShape(const Vec3f& center, float radius, int bsdf) {
  ShapeDescription s;
  s.type = ShapeDescription::Type::Sphere;
  s.center = center;
  s.radius = radius;
  s.bsdf = bsdf;
  return s;
}

// A closed diffuse sphere of albedo `albedo` that emits `radiance` towards its inside, seen from
// a 90-degree camera at the origin: radiance Le (1 - albedo^D) / (1 - albedo) everywhere for
// paths of at most D edges, and a path of k edges carries Le albedo^(k-1).
inline SceneDescription whiteFurnace(float albedo, int maxDepth,
                                     Spectrum radiance = Spectrum(1.0f, 0.5f, 2.0f), int size = 24,
                                     float radius = 1.5f,
                                     Vec3f center = Vec3f(0.1f, -0.05f, 0.2f)) {
  SceneDescription d;
  d.camera.toWorld = Matrix4::identity();
  d.camera.fovDegrees = 90;
  d.camera.width = d.camera.height = size;
  d.maxDepth = maxDepth;
  BsdfDescription b;
  b.reflectance = Spectrum(albedo);
  b.twoSided = true;
  d.bsdfs.push_back(b);
  ShapeDescription s;
  s.type = ShapeDescription::Type::Sphere;
  s.center = center;
  s.radius = radius;
  s.flipNormals = true;  // emit towards the inside
  s.bsdf = 0;
  s.isEmitter = true;
  s.radiance = radiance;
  d.shapes.push_back(s);
  return d;
}

// A floor seen obliquely from above, with a glass ball resting above it and a square light over
// the ball that the camera does not see: paths E D L, E D S S L (the ball's caustic), E S S D L
// (the floor through the ball), E S S D S S L (the caustic through the ball) and E S L (the
// light's glint), so that every perturbation applies to some of them, through curved glass where
// the Dirac lobes' solid-angle ratios do not cancel; and a light large enough that BDPT, where
// the reference and the seeds come from, converges on all of them.
// Writes that scene to a temporary file `name`, the camera at `origin` looking at `target`,
// with `extra` (an emitter, say) added: its path.
inline std::string writeGlassBallScene(const std::string& name, const std::string& origin,
                                       const std::string& target, const std::string& extra) {
  std::string p = (std::filesystem::temp_directory_path() / name).string();
  std::ofstream(p) << R"(<?xml version="1.0"?>
<scene version="0.5.0">
  <integrator type="path"><integer name="maxDepth" value="8"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="toWorld"><lookat origin=")"
                   << origin << R"(" target=")" << target << R"(" up="0, 1, 0"/>
    </transform>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/>
      <rfilter type="box"/></film>
  </sensor>
  <bsdf type="diffuse" id="floor"><rgb name="reflectance" value="0.7 0.6 0.5"/></bsdf>
  <bsdf type="dielectric" id="glass"><float name="intIOR" value="1.5"/></bsdf>
  <bsdf type="diffuse" id="black"><rgb name="reflectance" value="0 0 0"/></bsdf>
  <shape type="rectangle">
    <transform name="toWorld"><scale value="3"/><rotate x="1" angle="-90"/></transform>
    <ref id="floor"/>
  </shape>
  <shape type="sphere">
    <point name="center" x="0" y="0.9" z="0"/><float name="radius" value="0.4"/>
    <ref id="glass"/>
  </shape>
  <shape type="rectangle">
    <transform name="toWorld"><scale value="0.4"/><rotate x="1" angle="90"/>
      <translate y="2.2" z="0.5"/></transform>
    <ref id="black"/>
    <emitter type="area"><rgb name="radiance" value="20 20 20"/></emitter>
  </shape>
  )" << extra << R"(
</scene>
)";
  return p;
}
inline std::string glassBallScene() {
  static const std::string path =
      writeGlassBallScene("mlt_glass_ball.xml", "0, 2.5, -2.5", "0, 0.3, 0", "");
  return path;
}

// A 64 x 32 lat-long map: a blue gradient sky, a small sun (two by two texels from column
// sunColumn, rows 5 and 6) hundreds of times brighter, a dark ground.
inline std::shared_ptr<TextureImage> latLongSky(int sunColumn) {
  auto image = std::make_shared<TextureImage>();
  image->width = 64;
  image->height = 32;
  image->floats.resize(64 * 32 * 3);
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 64; ++x) {
      Spectrum c = y < 16 ? Spectrum(0.2f + 0.02f * y, 0.4f, 0.9f) : Spectrum(0.1f, 0.08f, 0.05f);
      if (y >= 5 && y <= 6 && x >= sunColumn && x <= sunColumn + 1) c = Spectrum(400, 350, 300);
      for (int k = 0; k < 3; ++k) image->floats[3 * (size_t(y) * 64 + x) + k] = c[k];
    }
  }
  return image;
}

// The same kind of sky as a 48 x 48 equal-area map (pbrt-v4's; warp.h): blue above the horizon
// (lighter towards it), the sun (400, 350, 300) within 5 degrees of theta 31 and phi 60 degrees,
// dark ground below; each texel the sky at its centre's direction.
inline std::shared_ptr<TextureImage> equalAreaSky() {
  auto image = std::make_shared<TextureImage>();
  const int n = 48;
  image->width = image->height = n;
  image->floats.resize(size_t(n) * n * 3);
  const float sunTheta = 31 * kPi / 180, sunPhi = 60 * kPi / 180;
  const Vec3f sun(std::sin(sunTheta) * std::cos(sunPhi), std::sin(sunTheta) * std::sin(sunPhi),
                  std::cos(sunTheta));
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const Vec3f w = equalAreaSquareToSphere(Vec2f((x + 0.5f) / n, (y + 0.5f) / n));
      Spectrum c =
          w.z > 0 ? Spectrum(0.2f + 0.3f * (1 - w.z), 0.4f, 0.9f) : Spectrum(0.1f, 0.08f, 0.05f);
      if (dot(w, sun) > std::cos(5 * kPi / 180)) c = Spectrum(400, 350, 300);
      for (int k = 0; k < 3; ++k) image->floats[3 * (size_t(y) * n + x) + k] = c[k];
    }
  }
  return image;
}

// A pbrt file (in the temporary folder, named by its light) of a grey box lit by `light` (pbrt
// world lines), seen from its open front; its path.
inline std::string litBoxScene(const std::string& light) {
  const std::string path =
      (std::filesystem::temp_directory_path() /
       ("farm_mutation_box_" + std::to_string(std::hash<std::string>()(light)) + ".pbrt"))
          .string();
  std::ofstream(path)
      << "LookAt 0 1.5 -2.5  0 1.5 3  0 1 0\nCamera \"perspective\" \"float fov\" 50\n"
         "Integrator \"path\" \"integer maxdepth\" 5\nWorldBegin\n"
         "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n"
         "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3  4 5 6 4 6 7  8 9 10 8 10 11  "
         "12 13 14 12 14 15  16 17 18 16 18 19]\n"
         "  \"point P\" [-1.5 0 -1  1.5 0 -1  1.5 0 3  -1.5 0 3"  // floor
         "  -1.5 3 -1  -1.5 3 3  1.5 3 3  1.5 3 -1"               // ceiling
         "  -1.5 0 3  1.5 0 3  1.5 3 3  -1.5 3 3"                 // back
         "  -1.5 0 -1  -1.5 0 3  -1.5 3 3  -1.5 3 -1"             // left
         "  1.5 0 -1  1.5 3 -1  1.5 3 3  1.5 0 3]\n" +            // right
             light;
  return path;
}

// Every area light of d `factor` times wider and deeper about its centre, its radiance divided by
// factor^2 so that it emits the same power: on the water caustic (200), BDPT's camera paths then
// reach the light through the water often enough to converge on L S D S E too.
inline void widenAreaLights(SceneDescription& d, float factor) {
  for (ShapeDescription& shape : d.shapes) {
    if (!shape.isEmitter) continue;
    Vec3f centre(0.0f);
    for (const Vec3f& p : shape.positions) centre += p;
    centre = centre / float(shape.positions.size());
    for (Vec3f& p : shape.positions) p = centre + (p - centre) * factor;
    shape.radiance = shape.radiance / (factor * factor);
  }
}

}  // namespace farm
