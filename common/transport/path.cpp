#include "common/transport/path.h"

#include <cmath>

#include "common/math/bytes.h"
#include "common/scene/scene.h"

namespace farm {

namespace {

// A product of RGB and scalar factors kept as rgb * exp(logScale), renormalized at every step:
// paths of hundreds of vertices, lights of 1e9 and scenes of 1e-4 units neither overflow nor
// underflow it.
class ScaledProduct {
 public:
  void multiply(const Spectrum& s) {
    for (int c = 0; c < 3; ++c) {
      if (!(s[c] >= 0) || !std::isfinite(s[c])) ok_ = false;
      rgb_[c] *= double(s[c]);
    }
    renormalize();
  }
  void multiply(double v) {
    if (!(v > 0) || !std::isfinite(v)) {
      ok_ = false;
      return;
    }
    logScale_ += std::log(v);
  }
  void fail() { ok_ = false; }
  bool finish(PathContribution* out) const {
    if (!ok_) return false;
    double lum = 0.2126 * rgb_[0] + 0.7152 * rgb_[1] + 0.0722 * rgb_[2];
    if (!(lum > 0)) return false;
    out->logLuminance = logScale_ + std::log(lum);
    out->color = Spectrum(float(rgb_[0] / lum), float(rgb_[1] / lum), float(rgb_[2] / lum));
    return true;
  }

 private:
  void renormalize() {
    double m = std::max(rgb_[0], std::max(rgb_[1], rgb_[2]));
    if (!(m > 0) || !std::isfinite(m)) {
      ok_ = false;
      return;
    }
    logScale_ += std::log(m);
    for (double& c : rgb_) c /= m;
  }
  double rgb_[3] = {1, 1, 1};
  double logScale_ = 0;
  bool ok_ = true;
};

constexpr uint32_t kPathMagic = 0x34485450;  // "PTH4": with texture coordinates, triangles, media
// The kind byte of the environment's vertex at infinity (beyond PathVertex::Kind's values, so
// that paths written before it read the same).
constexpr uint8_t kInfiniteLightKind = 4;

}  // namespace

double geometricConversion(const PathVertex& from, const PathVertex& to) {
  return toAreaDensity(1.0, from.p, to.p, to.n);
}

Path Path::fromSubpaths(const PathVertex* light, int s, const PathVertex* camera, int t) {
  Path path;
  path.vertices.reserve(size_t(s + t));
  for (int i = 0; i < s; ++i) path.vertices.push_back(light[i]);
  for (int i = t - 1; i >= 0; --i) path.vertices.push_back(camera[i]);
  return path;
}

bool Path::isSpecular(const Scene& scene, int i) const {
  const PathVertex& v = vertices[size_t(i)];
  return v.kind == PathVertex::Kind::Surface && v.shape >= 0 && scene.bsdfOf(v.shape).isDelta();
}

bool Path::isSeenEmission(const Scene& scene) const {
  if (length() != 1 || vertices[0].light < 0) return false;
  // A point light cannot be hit and the environment is not path-space MLT's: only area lights.
  const Light& light = scene.lights()[size_t(vertices[0].light)];
  return !light.isPoint() && !light.isEnvironment();
}

PathContribution Path::contribution(const Scene& scene, int maxDepth,
                                    const TransmittanceEstimator* estimator) const {
  PathContribution out;
  const int k = length();
  if (k < 1 || (maxDepth >= 0 && k > maxDepth)) return out;
  const PathVertex& x0 = vertices[0];
  const PathVertex& camera = vertices[size_t(k)];
  if (x0.light < 0 || camera.kind != PathVertex::Kind::Camera) return out;
  const bool media = scene.hasMedia();
  for (int i = 1; i < k; ++i) {
    const PathVertex::Kind kind = vertices[size_t(i)].kind;
    if (kind != PathVertex::Kind::Surface && !(media && kind == PathVertex::Kind::Medium))
      return out;
  }

  ScaledProduct f;
  // The media: each edge's transmittance, and the medium each vertex in one lies in.
  PathMedia walk;
  const TransmittanceEstimator marched{nullptr, 1, kDefaultMarchSteps};
  const TransmittanceEstimator& e = estimator ? *estimator : marched;
  if (media && e.marchSteps >= 0) {
    if (!this->media(scene, &walk)) return out;
    for (const PathMedia::Edge& edge : walk.edges) {
      for (const MediumSegment& seg : edge.segments) {
        const Medium& medium = scene.medium(seg.medium);
        if (medium.isHomogeneous() || e.marchSteps > 0 || !e.rng) {
          f.multiply(medium.marchedTransmittance(
              seg.start, seg.d, seg.length, e.marchSteps > 0 ? e.marchSteps : kDefaultMarchSteps));
        } else {
          IndependentSampler sampler(e.rng);
          Spectrum sum(0.0f);
          const int n = std::max(e.samples, 1);
          for (int j = 0; j < n; ++j)
            sum += medium.transmittance(seg.start, seg.d, seg.length, sampler, kLightStream);
          f.multiply(sum / float(n));
        }
      }
    }
  }
  // The unit direction between two vertices and their squared distance; an edge from the
  // environment has no distance (nor a sender's cosine): its x_0 is measured by direction, so
  // that G(x_0, x_1) is x_1's cosine alone.
  auto direction = [&](int from, int to, double* d2) {
    const PathVertex &a = vertices[size_t(from)], &b = vertices[size_t(to)];
    if (atInfinity(a) || atInfinity(b)) {
      *d2 = 1;
      return directionBetween(a, b);
    }
    Vec3f d = b.p - a.p;
    *d2 = double(lengthSquared(d));
    return d / std::sqrt(float(*d2));
  };
  // A point light has no cosine either (its intensity is per solid angle), and no camera sees
  // it: a path of one edge from it carries nothing.
  auto senderCosine = [&](const PathVertex& sender, const Vec3f& w) {
    return atInfinity(sender) || onPointLight(sender) || inMedium(sender)
               ? 1.0
               : double(absDot(sender.n, w));
  };
  if (k == 1 && onPointLight(x0)) return out;
  // Emission towards x_1.
  double d2;
  Vec3f w = direction(0, 1, &d2);
  if (!(d2 > 0)) return out;
  f.multiply(scene.lights().emitted(x0.light, x0.n, w));
  // Edges into surface vertices, and the scattering there.
  for (int i = 0; i + 1 < k; ++i) {
    const PathVertex& sender = vertices[size_t(i)];
    const PathVertex& v = vertices[size_t(i + 1)];
    w = direction(i, i + 1, &d2);
    f.multiply(senderCosine(sender, w) / d2);
    double d2Next;
    const Vec3f wo = direction(i + 1, i + 2, &d2Next);  // towards the camera
    const Vec3f wi = -w;                                // towards the light
    if (!(d2Next > 0)) return out;
    if (inMedium(v)) {
      // sigma_s times the phase function (a density per solid angle: no cosine).
      const int m = walk.edges.empty() ? v.medium : walk.edges[size_t(i + 1)].to;
      if (m < 0) return out;
      const Medium& medium = scene.medium(m);
      f.multiply(medium.sigmaS(v.p));
      f.multiply(double(medium.phase().eval(wo, wi)));
      continue;
    }
    if (!scene.sidesAgree(wi, v.n, v.ns) || !scene.sidesAgree(wo, v.n, v.ns)) return out;
    const Bsdf& bsdf = scene.bsdfAt(v.shape, v.uv);
    Frame frame(v.ns);
    Vec3f lo = frame.toLocal(wo), li = frame.toLocal(wi);
    if (bsdf.isDelta()) {
      // The delta's coefficient over |cos|, times the receiving cosine: the lobe's value.
      bool reflection;
      float probability;
      Spectrum value;
      if (!bsdf.specularLobe(lo, li, TransportMode::Radiance, &reflection, &probability, &value))
        return out;
      f.multiply(value);
    } else {
      f.multiply(bsdf.eval(lo, li, TransportMode::Radiance));
      f.multiply(double(std::fabs(li.z)));
    }
  }
  // The camera's edge: importance per unit solid angle, the sender's cosine over d^2, and the
  // pixel count of the splat convention.
  const PathVertex& last = vertices[size_t(k - 1)];
  w = direction(k - 1, k, &d2);
  const Camera& cam = scene.camera();
  const Vec3f& lens = vertices[size_t(k)].p;
  if (!cam.project(lens, -w, &out.film)) return out;
  f.multiply(double(cam.importance(lens, -w)) * senderCosine(last, w) / d2 *
             double(cam.pixelCount()));
  if (!f.finish(&out)) out.logLuminance = -INFINITY;
  return out;
}

bool Path::media(const Scene& scene, PathMedia* out) const {
  const int k = length();
  out->edges.assign(size_t(std::max(k, 0)), PathMedia::Edge());
  int around = scene.cameraMedium();  // the medium around x_{i+1}
  for (int i = k - 1; i >= 0; --i) {
    const PathVertex &a = vertices[size_t(i + 1)], &b = vertices[size_t(i)];
    PathMedia::Edge& edge = out->edges[size_t(i)];
    edge.from = a.kind == PathVertex::Kind::Surface
                    ? scene.mediumOnSide(a.shape, a.n, b.p - a.p, around)
                    : around;
    if (!scene.mediumSegments(a.p, a.n, b.p, b.n, edge.from, &edge.segments, &edge.to))
      return false;
    if (inMedium(b) && edge.to < 0) return false;
    around = edge.to;
  }
  return true;
}

double Path::freeFlightDensity(const Scene& scene, const PathMedia& media, int j,
                               bool fromLight) const {
  // The edge it flies along, with the stretches in the order of the flight.
  const PathMedia::Edge& edge = media.edges[size_t(fromLight ? j - 1 : j)];
  const int n = int(edge.segments.size());
  const bool lands = inMedium(vertices[size_t(j)]);
  if (n == 0) return lands ? 0.0 : 1.0;
  double p = 1;
  for (int q = 0; q < n; ++q) {
    // Stretches run from x_{j} (fromLight) or towards it (from the camera side).
    const MediumSegment& s = edge.segments[size_t(fromLight ? n - 1 - q : q)];
    const bool last = q == n - 1;
    // The flight's own direction: the reverse of the stretch's when flying from the light.
    const Vec3f o = fromLight ? s.start + s.d * s.length : s.start;
    const Vec3f d = fromLight ? -s.d : s.d;
    p *= scene.medium(s.medium).freeFlightDensity(o, d, s.length, last && lands);
  }
  return p;
}

void Path::densities(const Scene& scene, double* pL, double* pE, char* delta) const {
  std::vector<const PathVertex*> pointers;
  pointers.reserve(vertices.size());
  for (const PathVertex& v : vertices) pointers.push_back(&v);
  pathDensities(scene, pointers.data(), int(pointers.size()), pL, pE, delta);
}

std::string Path::serialize() const {
  std::string s;
  appendBytes(s, kPathMagic);
  appendBytes(s, uint32_t(vertices.size()));
  for (const PathVertex& v : vertices) {
    // The environment's vertex at infinity is a light vertex of its own kind on the wire.
    appendBytes(s, atInfinity(v) ? kInfiniteLightKind : uint8_t(v.kind));
    for (const Vec3f* x : {&v.p, &v.n, &v.ns}) appendBytes(s, *x);
    appendBytes(s, v.uv);
    appendBytes(s, int32_t(v.shape));
    appendBytes(s, int32_t(v.light));
    appendBytes(s, int32_t(v.primitive));
    appendBytes(s, int32_t(v.medium));
  }
  return s;
}

bool Path::deserialize(const std::string& bytes, const Scene& scene) {
  size_t at = 0;
  uint32_t magic, count;
  if (!readBytes(bytes, at, &magic) || magic != kPathMagic || !readBytes(bytes, at, &count))
    return false;
  constexpr size_t kVertexBytes = 1 + 11 * sizeof(float) + 4 * sizeof(int32_t);
  if (count < 2 || count > (bytes.size() - at) / kVertexBytes) return false;
  const int shapes = int(scene.description().shapes.size());
  const int lights = int(scene.lights().size());
  std::vector<PathVertex> read(count);
  for (uint32_t i = 0; i < count; ++i) {
    PathVertex& v = read[i];
    uint8_t kind;
    int32_t shape, light, primitive, medium;
    if (!readBytes(bytes, at, &kind) || !readBytes(bytes, at, &v.p) ||
        !readBytes(bytes, at, &v.n) || !readBytes(bytes, at, &v.ns) ||
        !readBytes(bytes, at, &v.uv) || !readBytes(bytes, at, &shape) ||
        !readBytes(bytes, at, &light) || !readBytes(bytes, at, &primitive) ||
        !readBytes(bytes, at, &medium))
      return false;
    if (kind > uint8_t(PathVertex::Kind::Medium) && kind != kInfiniteLightKind) return false;
    v.infinite = kind == kInfiniteLightKind;
    v.kind = v.infinite ? PathVertex::Kind::Light : PathVertex::Kind(kind);
    v.shape = shape;
    v.light = light;
    v.primitive = primitive;
    v.medium = medium;
    if (!isFinite(v.p) || !isFinite(v.n) || !isFinite(v.ns) || !std::isfinite(v.uv.x) ||
        !std::isfinite(v.uv.y))
      return false;
    if (medium < -1 || medium >= int(scene.description().media.size())) return false;
    const bool isCamera = v.kind == PathVertex::Kind::Camera;
    if (isCamera != (i + 1 == count)) return false;  // the camera, and only it, ends the path
    if (inMedium(v)) {
      // A scattering point inside a medium: no surface, no normals, never an end.
      if (i == 0 || medium < 0 || shape != -1 || light != -1 || primitive != -1 ||
          lengthSquared(v.n) != 0 || lengthSquared(v.ns) != 0)
        return false;
    } else if (v.infinite) {
      // The environment's direction: only x_0, a unit direction.
      if (i != 0 || light != scene.lights().environmentLight() || light < 0 || shape != -1 ||
          primitive != -1 || medium != -1 || std::fabs(farm::length(v.n) - 1) > 1e-3f)
        return false;
    } else if (!isCamera && shape == -1 && i == 0 && v.kind == PathVertex::Kind::Light) {
      // A point light's position (it has no shape).
      if (light < 0 || light >= lights || !scene.lights()[size_t(light)].isPoint() ||
          primitive != -1)
        return false;
    } else if (!isCamera) {
      if (shape < 0 || shape >= shapes) return false;
      if (light != scene.lightOf(shape)) return false;
      if (primitive < -1 || primitive >= scene.primitiveCount(shape)) return false;
    } else if (shape != -1 || light != -1 || primitive != -1 || !scene.camera().onLens(v.p)) {
      return false;
    }
  }
  if (read[0].light < 0 || at != bytes.size() || lights == 0) return false;
  vertices = std::move(read);
  return true;
}

}  // namespace farm
