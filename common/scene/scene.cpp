#include "common/scene/scene.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "common/sampling/warp.h"

namespace farm {

namespace {

void throwOnEmbreeError(RTCDevice device, const char* what) {
  RTCError err = rtcGetDeviceError(device);
  if (err != RTC_ERROR_NONE) {
    throw std::runtime_error(std::string("Embree error ") + std::to_string(int(err)) + " in " +
                             what);
  }
}

float triangleArea(const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  return 0.5f * length(cross(b - a, c - a));
}

// Geometric and shading normal of triangle `prim` at barycentric weights (w0, w1, w2) of its
// vertices. The vertex normals, when used (smooth shading), also say where the outside is, so
// the geometric normal is turned to their side; flipNormals turns both. False for a degenerate
// triangle. Intersection and light sampling share it: the emitting side must be the same.
bool triangleNormals(const ShapeDescription& s, uint32_t prim, float w0, float w1, float w2,
                     Vec3f* ngOut, Vec3f* nsOut) {
  const uint32_t* tri = &s.indices[3 * size_t(prim)];
  const Vec3f &a = s.positions[tri[0]], &b = s.positions[tri[1]], &c = s.positions[tri[2]];
  Vec3f ng = cross(b - a, c - a);
  float len = length(ng);
  if (!(len > 0)) return false;
  ng = ng / len;
  Vec3f ns = ng;
  if (!s.faceNormals && !s.normals.empty()) {
    Vec3f n = s.normals[tri[0]] * w0 + s.normals[tri[1]] * w1 + s.normals[tri[2]] * w2;
    float nl = length(n);
    if (nl > 0 && std::isfinite(nl)) {
      ns = n / nl;
      if (dot(ns, ng) < 0) ng = -ng;
    }
  }
  *ngOut = s.flipNormals ? -ng : ng;
  *nsOut = s.flipNormals ? -ns : ns;
  return true;
}

// Whether the mesh's shading normal is continuous: wherever corners of its triangles meet
// (vertices shared, or apart at one position, as a flat-shaded export splits them), their
// shading normals (triangleNormals at the corner) agree to within about half a degree.
bool continuousShading(const ShapeDescription& s) {
  struct Key {
    float x, y, z;
    bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
  };
  struct Hash {
    size_t operator()(const Key& k) const {
      uint32_t b[3];
      std::memcpy(b, &k, sizeof(b));
      return size_t(b[0]) * 73856093u ^ size_t(b[1]) * 19349663u ^ size_t(b[2]) * 83492791u;
    }
  };
  std::unordered_map<Key, Vec3f, Hash> normalAt;
  normalAt.reserve(s.positions.size());
  const float weights[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (uint32_t t = 0; t < s.indices.size() / 3; ++t) {
    for (int corner = 0; corner < 3; ++corner) {
      Vec3f ng, ns;
      if (!triangleNormals(s, t, weights[corner][0], weights[corner][1], weights[corner][2], &ng,
                           &ns))
        break;  // a degenerate triangle meets nothing
      const Vec3f& p = s.positions[s.indices[3 * size_t(t) + size_t(corner)]];
      // (+ 0: minus zero is zero, and must hash as zero does)
      const auto [it, inserted] = normalAt.emplace(Key{p.x + 0.0f, p.y + 0.0f, p.z + 0.0f}, ns);
      if (!inserted && dot(it->second, ns) < 0.99996f) return false;  // cos 0.5 degrees
    }
  }
  return true;
}

// An Embree ray from o along d up to tFar; with a hit record, no hit yet.
RTCRay embreeRay(const Vec3f& o, const Vec3f& d, float tFar) {
  RTCRay ray;
  ray.org_x = o.x, ray.org_y = o.y, ray.org_z = o.z;
  ray.dir_x = d.x, ray.dir_y = d.y, ray.dir_z = d.z;
  ray.tnear = 0;
  ray.tfar = tFar;
  ray.mask = 0xFFFFFFFFu;
  ray.flags = 0;
  ray.time = 0;
  return ray;
}
RTCRayHit embreeRayHit(const Vec3f& o, const Vec3f& d, float tFar) {
  RTCRayHit rh;
  rh.ray = embreeRay(o, d, tFar);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

// A point of primitive t of shape s (a whole sphere, or triangle t of a mesh), uniform by area
// from u, and its normal (the emitting side's, for lights). False for a degenerate triangle.
bool pointOnPrimitive(const ShapeDescription& s, uint32_t t, const Vec2f& u, Vec3f* p, Vec3f* n) {
  if (s.type == ShapeDescription::Type::Sphere) {
    const Vec3f d = squareToUniformSphere(u);
    *p = s.center + d * s.radius;
    *n = s.flipNormals ? -d : d;
    return true;
  }
  const uint32_t* tri = &s.indices[3 * size_t(t)];
  const Vec3f &a = s.positions[tri[0]], &b = s.positions[tri[1]], &c = s.positions[tri[2]];
  const Vec2f bary = squareToTriangle(u);
  *p = a * bary.x + b * bary.y + c * (1 - bary.x - bary.y);
  Vec3f ns;
  return triangleNormals(s, t, bary.x, bary.y, 1 - bary.x - bary.y, n, &ns);
}

}  // namespace

Scene::Scene(SceneDescription desc) : desc_(std::move(desc)), camera_(desc_.camera) {
  // Textures refer only to earlier ones (no cycles), and every reference is in range: what the
  // loaders guarantee, checked here for descriptions built by hand.
  const int numTextures = int(desc_.textures.size());
  for (int i = 0; i < numTextures; ++i) {
    const TextureDescription& t = desc_.textures[size_t(i)];
    bool ok = true;
    if (t.type == TextureDescription::Type::Image) ok = t.image && t.image->width > 0;
    if (t.type == TextureDescription::Type::Checkerboard ||
        t.type == TextureDescription::Type::Scale)
      ok = t.tex1 >= 0 && t.tex1 < i && t.tex2 >= 0 && t.tex2 < i;
    if (!ok) throw std::invalid_argument("texture " + std::to_string(i) + " is malformed");
  }
  for (const BsdfDescription& b : desc_.bsdfs) {
    if (b.reflectanceTexture >= numTextures)
      throw std::invalid_argument("a BSDF refers to texture " +
                                  std::to_string(b.reflectanceTexture) + " of " +
                                  std::to_string(numTextures));
    bsdfs_.emplace_back(b);
  }
  bsdfs_.emplace_back(BsdfDescription{});  // default diffuse for shapes without a bsdf

  // Media, and the references to them, checked for descriptions built by hand too.
  const int numMedia = int(desc_.media.size());
  for (const MediumDescription& m : desc_.media) {
    const std::string problem = mediumProblem(m);
    if (!problem.empty())
      throw std::invalid_argument("medium " + (m.origin.empty() ? m.id : m.origin) + ": " +
                                  problem);
    media_.emplace_back(m);
  }
  auto mediumInRange = [&](int m) { return m >= -1 && m < numMedia; };
  if (!mediumInRange(desc_.camera.medium))
    throw std::invalid_argument("the camera's medium " + std::to_string(desc_.camera.medium) +
                                " is not one of the scene's " + std::to_string(numMedia));
  tracksMedia_ = numMedia > 0;
  for (const ShapeDescription& s : desc_.shapes) {
    if (!mediumInRange(s.interiorMedium) || !mediumInRange(s.exteriorMedium))
      throw std::invalid_argument("shape " + s.origin +
                                  " refers to a medium that is not one of the "
                                  "scene's " +
                                  std::to_string(numMedia));
    if (s.nullBoundary && s.isEmitter)
      throw std::invalid_argument("shape " + s.origin +
                                  " emits light and is a null medium boundary: give it a BSDF");
    tracksMedia_ = tracksMedia_ || s.nullBoundary;
  }

  RTCDevice device = rtcNewDevice(nullptr);
  if (!device) throw std::runtime_error("Embree: cannot create a device");
  device_ = device;
  RTCScene scene = rtcNewScene(device);
  scene_ = scene;
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
  hasNullBoundaries_ = std::any_of(desc_.shapes.begin(), desc_.shapes.end(),
                                   [](const ShapeDescription& s) { return s.nullBoundary; });

  Vec3f lo(kInfinity), hi(-kInfinity);
  const int n = int(desc_.shapes.size());
  shapeBsdf_.resize(n);
  shapeLight_.assign(n, -1);
  for (int i = 0; i < n; ++i) {
    const ShapeDescription& s = desc_.shapes[i];
    if (!s.uvs.empty() && s.uvs.size() != s.positions.size())
      throw std::invalid_argument("shape " + std::to_string(i) + " has " +
                                  std::to_string(s.uvs.size()) + " texture coordinates for " +
                                  std::to_string(s.positions.size()) + " vertices");
    int b = s.bsdf;
    shapeBsdf_[i] = (b >= 0 && b < int(desc_.bsdfs.size())) ? b : int(bsdfs_.size()) - 1;
    double area = 0;
    std::vector<double> cdf;  // an emitting mesh's running triangle area
    RTCGeometry geom;
    if (s.type == ShapeDescription::Type::Sphere) {
      geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
      float* v = static_cast<float*>(rtcSetNewGeometryBuffer(
          geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
      v[0] = s.center.x, v[1] = s.center.y, v[2] = s.center.z, v[3] = s.radius;
      area = 4 * kPi * s.radius * s.radius;
      lo = vmin(lo, s.center - Vec3f(s.radius));
      hi = vmax(hi, s.center + Vec3f(s.radius));
    } else {
      const size_t nv = s.positions.size(), nt = s.indices.size() / 3;
      geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      // Embree reads the description's own arrays, which the scene keeps unchanged for its
      // life, instead of copies of them. It may load a buffer's last element 16 bytes at a
      // time, so each allocation holds a little more than the mesh.
      static_assert(sizeof(Vec3f) == 3 * sizeof(float), "Embree's FLOAT3 vertices are packed");
      std::vector<Vec3f>& positions = desc_.shapes[size_t(i)].positions;
      positions.reserve(nv + 1);
      rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                 positions.data(), 0, sizeof(Vec3f), nv);
      for (size_t k = 0; k < nv; ++k) {
        lo = vmin(lo, s.positions[k]);
        hi = vmax(hi, s.positions[k]);
      }
      std::vector<uint32_t>& indices = desc_.shapes[size_t(i)].indices;
      indices.reserve(3 * nt + 4);  // the same for the indices
      rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices.data(),
                                 0, 3 * sizeof(uint32_t), nt);
      if (s.isEmitter) {
        cdf.reserve(nt);
        for (size_t t = 0; t < nt; ++t) {
          area +=
              double(triangleArea(s.positions[s.indices[3 * t]], s.positions[s.indices[3 * t + 1]],
                                  s.positions[s.indices[3 * t + 2]]));
          cdf.push_back(area);
        }
      }
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(scene, geom, unsigned(i));
    rtcReleaseGeometry(geom);
    throwOnEmbreeError(device, "building the scene geometry");

    if (s.isEmitter && area > 0 && luminance(s.radiance) > 0)
      shapeLight_[i] = lights_.addShape(i, s.radiance, area, s.emitsBothSides, std::move(cdf));
  }
  // Specular surfaces by area (a sphere as one entry).
  double specularArea = 0;
  smoothSpecular_.assign(size_t(n), 0);
  for (int i = 0; i < n; ++i) {
    if (!bsdfs_[size_t(shapeBsdf_[i])].isDelta()) continue;
    const ShapeDescription& s = desc_.shapes[size_t(i)];
    smoothSpecular_[size_t(i)] =
        s.type == ShapeDescription::Type::Sphere || continuousShading(s) ? 1 : 0;
    anySmoothSpecular_ |= smoothSpecular_[size_t(i)] != 0;
    if (s.type == ShapeDescription::Type::Sphere) {
      specularArea += 4 * kPi * double(s.radius) * s.radius;
      specularCdf_.push_back(specularArea);
      specularPrimitives_.emplace_back(i, 0);
      continue;
    }
    for (size_t t = 0; t < s.indices.size() / 3; ++t) {
      const double a =
          double(triangleArea(s.positions[s.indices[3 * t]], s.positions[s.indices[3 * t + 1]],
                              s.positions[s.indices[3 * t + 2]]));
      if (!(a > 0)) continue;
      specularArea += a;
      specularCdf_.push_back(specularArea);
      specularPrimitives_.emplace_back(i, uint32_t(t));
    }
  }
  rtcCommitScene(scene);
  throwOnEmbreeError(device, "committing the scene");
  if (n > 0) extent_ = std::max(1e-6f, 0.5f * length(hi - lo));
  if (n > 0) center_ = (lo + hi) * 0.5f;
  if (!std::isfinite(extent_) || !isFinite(center_)) extent_ = 1, center_ = Vec3f(0.0f);

  if (desc_.environment.present)
    lights_.addEnvironment(std::make_unique<EnvironmentLight>(desc_.environment),
                           desc_.environment.scale, extent_);
  for (const PointLightDescription& p : desc_.pointLights)
    lights_.addPoint(PointLight(p), p.intensity);
  lights_.finish(center_, extent_);

  reach_ = std::max(extent_, length(camera_.position() - center_));
  for (const PointLight& p : lights_.pointLights())
    reach_ = std::max(reach_, length(p.position() - center_));
  if (!std::isfinite(reach_)) reach_ = kInfinity;
}

Scene::~Scene() {
  if (scene_) rtcReleaseScene(static_cast<RTCScene>(scene_));
  if (device_) rtcReleaseDevice(static_cast<RTCDevice>(device_));
}

float Scene::offsetFor(const Vec3f& p) const {
  // Relative to the magnitude of the coordinates (float rounding of the hit point) and to the
  // scene's size, so that huge and tiny scenes behave alike.
  return 1e-5f * (maxAbsComponent(p) + extent_);
}

Ray Scene::spawnRay(const Vec3f& p, const Vec3f& ng, const Vec3f& d) const {
  Ray r;
  float side = dot(ng, d) >= 0 ? 1.0f : -1.0f;
  r.o = p + ng * (side * offsetFor(p));
  r.d = d;
  return r;
}

bool Scene::intersect(const Ray& r, SurfaceHit* hit) const {
  return intersect(r, hit, true);
}

bool Scene::intersect(const Ray& r, SurfaceHit* hit, bool everyShape) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh = embreeRayHit(r.o, r.d, r.tMax);
  rtcIntersect1(static_cast<RTCScene>(scene_), &context, &rh);
  if (rayLog_)
    rayLog_->rays.push_back({r.o, r.d, r.tMax, false, rh.hit.geomID != RTC_INVALID_GEOMETRY_ID});
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;

  const int shape = int(rh.hit.geomID);
  const ShapeDescription& s = desc_.shapes[shape];
  hit->shape = shape;
  hit->primitive = rh.hit.primID;
  hit->t = rh.ray.tfar;
  if (!everyShape && !s.nullBoundary) return true;
  if (s.type == ShapeDescription::Type::Sphere) {
    Vec3f p = r.o + r.d * rh.ray.tfar;
    Vec3f n = normalize(p - s.center);
    hit->p = s.center + n * s.radius;  // back onto the surface
    hit->ng = s.flipNormals ? -n : n;
    hit->ns = hit->ng;
    hit->uv = Vec2f(0, 0);
  } else {
    float u = rh.hit.u, v = rh.hit.v;
    // Along the ray rather than by the barycentrics: a point interpolated between the vertices
    // carries their rounding (1e-4 on a ground plane a few thousand units wide), enough to move
    // a grazing hit's direction to the camera off the pixel it was traced through; o + t d errs
    // only by the rounding of t, along the ray. The spawn offsets cover either.
    hit->p = r.o + r.d * rh.ray.tfar;
    if (!triangleNormals(s, rh.hit.primID, 1 - u - v, u, v, &hit->ng, &hit->ns)) return false;
    hit->uv = Vec2f(0, 0);
    if (!s.uvs.empty()) {
      const uint32_t* tri = &s.indices[3 * size_t(rh.hit.primID)];
      const Vec2f &a = s.uvs[tri[0]], &b = s.uvs[tri[1]], &c = s.uvs[tri[2]];
      const float w = 1 - u - v;
      hit->uv = Vec2f(w * a.x + u * b.x + v * c.x, w * a.y + u * b.y + v * c.y);
    }
  }
  return true;
}

int Scene::primitiveCount(int shape) const {
  const ShapeDescription& s = desc_.shapes[size_t(shape)];
  return s.type == ShapeDescription::Type::Sphere ? 1 : int(s.indices.size() / 3);
}

bool Scene::surfaceDifferential(int shape, int primitive, const Vec3f& p, const Vec3f& ng,
                                SurfaceDifferential* out) const {
  if (shape < 0 || shape >= int(desc_.shapes.size())) return false;
  const ShapeDescription& s = desc_.shapes[size_t(shape)];
  const Frame tangent(ng);
  out->dpdu = tangent.s;
  out->dpdv = tangent.t;
  if (s.type == ShapeDescription::Type::Sphere) {
    // ns = +-(p - c) / r: it turns by d / r along a tangent d.
    const float sign = s.flipNormals ? -1.0f : 1.0f;
    out->ns = normalize(p - s.center) * sign;
    out->dndu = out->dpdu * (sign / s.radius);
    out->dndv = out->dpdv * (sign / s.radius);
    return true;
  }
  if (primitive < 0 || primitive >= primitiveCount(shape)) return false;
  const uint32_t* tri = &s.indices[3 * size_t(primitive)];
  const Vec3f &a = s.positions[tri[0]], &b = s.positions[tri[1]], &c = s.positions[tri[2]];
  const Vec3f e1 = b - a, e2 = c - a, n = cross(e1, e2);
  const float n2 = lengthSquared(n);
  if (!(n2 > 0)) return false;
  // Gradients of the barycentric weights of b and c over the triangle's plane (dual basis).
  const Vec3f g1 = cross(e2, n) / n2, g2 = cross(n, e1) / n2;
  const float w1 = dot(p - a, g1), w2 = dot(p - a, g2);
  Vec3f ngUnused, ns;
  if (!triangleNormals(s, uint32_t(primitive), 1 - w1 - w2, w1, w2, &ngUnused, &ns)) return false;
  out->ns = ns;
  out->dndu = out->dndv = Vec3f(0.0f);
  if (s.faceNormals || s.normals.empty()) return true;
  const Vec3f &n0 = s.normals[tri[0]], &n1 = s.normals[tri[1]], &n2v = s.normals[tri[2]];
  const Vec3f interpolated = n0 * (1 - w1 - w2) + n1 * w1 + n2v * w2;
  const float len = length(interpolated);
  if (!(len > 0) || !std::isfinite(len)) return true;  // triangleNormals fell back to the face's
  const Vec3f unit = interpolated / len;
  // d(N / |N|) = (dN - unit (unit . dN)) / |N|, with dN the change of the interpolated normal
  // along the tangent; flipNormals turns both.
  const float sign = s.flipNormals ? -1.0f : 1.0f;
  for (int k = 0; k < 2; ++k) {
    const Vec3f d = k == 0 ? out->dpdu : out->dpdv;
    const Vec3f dN = (n1 - n0) * dot(g1, d) + (n2v - n0) * dot(g2, d);
    const Vec3f dn = (dN - unit * dot(unit, dN)) * (sign / len);
    (k == 0 ? out->dndu : out->dndv) = dn;
  }
  return true;
}

bool Scene::sampleSpecularSurface(const float u[3], Vec3f* p, Vec3f* n) const {
  if (specularCdf_.empty()) return false;
  const double target = double(u[0]) * specularCdf_.back();
  size_t k = size_t(std::upper_bound(specularCdf_.begin(), specularCdf_.end(), target) -
                    specularCdf_.begin());
  k = std::min(k, specularCdf_.size() - 1);
  const auto [shape, t] = specularPrimitives_[k];
  return pointOnPrimitive(desc_.shapes[size_t(shape)], t, {u[1], u[2]}, p, n);
}

Bsdf Scene::bsdfAt(int shape, const Vec2f& uv) const {
  Bsdf bsdf = bsdfs_[shapeBsdf_[shape]];
  const int texture = bsdf.reflectanceTexture();
  if (texture >= 0) bsdf.setReflectance(evalTexture(desc_.textures, texture, uv));
  return bsdf;
}

void Scene::offsetEnds(const Vec3f& p0, const Vec3f& n0, const Vec3f& p1, const Vec3f& n1, Vec3f* o,
                       Vec3f* e) const {
  const Vec3f d = p1 - p0;
  *o = p0, *e = p1;
  if (lengthSquared(n0) > 0) *o = p0 + n0 * ((dot(n0, d) >= 0 ? 1.0f : -1.0f) * offsetFor(p0));
  if (lengthSquared(n1) > 0) *e = p1 + n1 * ((dot(n1, d) <= 0 ? 1.0f : -1.0f) * offsetFor(p1));
}

bool Scene::occluded(const Vec3f& o, const Vec3f& d, float tFar) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray = embreeRay(o, d, tFar);
  rtcOccluded1(static_cast<RTCScene>(scene_), &context, &ray);
  if (rayLog_) rayLog_->rays.push_back({o, d, tFar, true, ray.tfar < 0});
  return ray.tfar < 0;  // Embree sets tfar to -inf on a hit
}

int64_t Scene::traceLoggedRays(const RayLog& log) const {
  int64_t hits = 0;
  for (const RayLog::Entry& e : log.rays) {
    RTCIntersectContext context;  // as intersect() and occluded() make it, each ray its own
    rtcInitIntersectContext(&context);
    RTCRayHit rh = embreeRayHit(e.o, e.d, e.tFar);
    if (e.occlusion) {
      rtcOccluded1(static_cast<RTCScene>(scene_), &context, &rh.ray);
      hits += rh.ray.tfar < 0;
    } else {
      rtcIntersect1(static_cast<RTCScene>(scene_), &context, &rh);
      hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
  }
  return hits;
}

bool Scene::visible(const Vec3f& p0, const Vec3f& n0, const Vec3f& p1, const Vec3f& n1) const {
  Vec3f o, e;
  offsetEnds(p0, n0, p1, n1, &o, &e);
  // The whole segment between the offset end points (t up to 1 along e - o): trimming it by a
  // fraction of its length as well would let light through occluders near the far end of long
  // rays.
  const Vec3f d = e - o;
  return !occluded(o, d, 1.0f);
}

bool Scene::escapes(const Vec3f& p, const Vec3f& ng, const Vec3f& w) const {
  const Vec3f o = spawnRay(p, ng, w).o;
  return !occluded(o, w, kInfinity);
}

int Scene::mediumOnSide(int shape, const Vec3f& ng, const Vec3f& w, int current) const {
  const ShapeDescription& s = desc_.shapes[size_t(shape)];
  if (!s.hasMediumInterface) return current;
  return dot(w, ng) > 0 ? s.exteriorMedium : s.interiorMedium;
}

int Scene::mediumAt(const Vec3f& p) const {
  if (!tracksMedia_) return -1;
  // A direction along no axis, so that the ray does not run along the edges of boxes.
  const Vec3f d = normalize(Vec3f(0.5477f, 0.6412f, 0.5373f));
  Ray r{p, d, kInfinity};
  for (int crossing = 0; crossing < 1024; ++crossing) {
    SurfaceHit hit;
    if (!intersect(r, &hit)) return -1;
    const ShapeDescription& s = desc_.shapes[size_t(hit.shape)];
    if (s.hasMediumInterface) return dot(d, hit.ng) > 0 ? s.interiorMedium : s.exteriorMedium;
    r = spawnRay(hit.p, hit.ng, d);
  }
  return -1;
}

bool Scene::walkMedia(Vec3f start, Vec3f o, Vec3f d, const Vec3f* end, const Vec3f* rayEnd,
                      int medium, const SegmentVisitor& visit, int* arrival) const {
  // Each pass crosses one null boundary; a cap keeps a degenerate stack of them finite. The
  // rays start off the surfaces (o, rayEnd) and aim at rayEnd itself, as visible()'s does: a
  // ray along the unoffset points' direction would pass an offset's width beside rayEnd and
  // could clip the end's own surface. The media count from the surfaces themselves (start,
  // end), or a crossing would skip the offset's length of each medium.
  for (int crossing = 0; crossing < 1024; ++crossing) {
    Ray r{o, d, kInfinity};
    if (rayEnd) {
      const Vec3f toEnd = *rayEnd - o;
      r.tMax = farm::length(toEnd);
      if (!(r.tMax > 0)) {
        if (arrival) *arrival = medium;
        return true;
      }
      r.d = d = toEnd / r.tMax;
    }
    // Without null boundaries there is nothing to cross, and one occlusion ray decides, the
    // shadow ray of a walk in vacuum; with them, a closest hit, whose normals are worked out
    // only for a boundary (any other surface blocks the way). A closest hit with normals for
    // every shadow ray in a medium cost pt 1.2x and bdpt 1.4x their speed in a boundless one
    // (farm_plan_bench, Media).
    SurfaceHit hit;
    bool found = false;
    if (hasNullBoundaries_) {
      found = intersect(r, &hit, false);
      if (found && !desc_.shapes[size_t(hit.shape)].nullBoundary) return false;
    } else if (occluded(r.o, r.d, r.tMax)) {
      return false;
    }
    if (medium >= 0) {
      const float length =
          found ? farm::length(hit.p - start) : (end ? farm::length(*end - start) : kInfinity);
      if (!visit(MediumSegment{medium, start, d, length})) return false;
    }
    if (!found) {
      if (arrival) *arrival = medium;
      return true;
    }
    medium = mediumOnSide(hit.shape, hit.ng, d, medium);
    start = hit.p;
    o = spawnRay(hit.p, hit.ng, d).o;
  }
  return false;
}

Spectrum Scene::transmittanceAlong(Vec3f start, Vec3f o, Vec3f d, const Vec3f* end,
                                   const Vec3f* rayEnd, int medium, Sampler& sampler,
                                   SampleStream stream) const {
  Spectrum T(1.0f);
  const bool reached = walkMedia(
      start, o, d, end, rayEnd, medium,
      [&](const MediumSegment& s) {
        T *= media_[size_t(s.medium)].transmittance(s.start, s.d, s.length, sampler, stream);
        return !isBlack(T);
      },
      nullptr);
  return reached ? T : Spectrum(0.0f);
}

bool Scene::mediumSegments(const Vec3f& p0, const Vec3f& n0, const Vec3f& p1, const Vec3f& n1,
                           int medium, std::vector<MediumSegment>* segments, int* arrival) const {
  segments->clear();
  const Vec3f d = p1 - p0;
  if (!(lengthSquared(d) > 0)) return false;
  Vec3f o, e;
  offsetEnds(p0, n0, p1, n1, &o, &e);
  return walkMedia(
      p0, o, normalize(d), &p1, &e, medium,
      [&](const MediumSegment& s) {
        segments->push_back(s);
        return true;
      },
      arrival);
}

Spectrum Scene::transmittance(const Vec3f& p0, const Vec3f& n0, const Vec3f& p1, const Vec3f& n1,
                              int medium, Sampler& sampler, SampleStream stream) const {
  if (!tracksMedia_) return visible(p0, n0, p1, n1) ? Spectrum(1.0f) : Spectrum(0.0f);
  // The ray's end points offset off their surfaces as visible()'s are.
  const Vec3f d = p1 - p0;
  Vec3f o, e;
  offsetEnds(p0, n0, p1, n1, &o, &e);
  if (!(lengthSquared(d) > 0)) return Spectrum(1.0f);
  return transmittanceAlong(p0, o, normalize(d), &p1, &e, medium, sampler, stream);
}

Spectrum Scene::transmittanceToInfinity(const Vec3f& p, const Vec3f& n, const Vec3f& w, int medium,
                                        Sampler& sampler, SampleStream stream) const {
  if (!tracksMedia_) return escapes(p, n, w) ? Spectrum(1.0f) : Spectrum(0.0f);
  const Vec3f o = lengthSquared(n) > 0 ? spawnRay(p, n, w).o : p;
  return transmittanceAlong(p, o, w, nullptr, nullptr, medium, sampler, stream);
}

void Scene::sampleLightPoint(int light, const float u[3], Vec3f* p, Vec3f* n) const {
  const ShapeDescription& s = desc_.shapes[size_t(lights_[light].shape)];
  pointOnPrimitive(s, lights_.pickTriangle(light, u[0]), {u[1], u[2]}, p, n);
}

}  // namespace farm
