#pragma once
// Participating media: where along a ray light scatters or is absorbed, and how much of it a
// segment lets through. The estimators are the unbiased ones of Novak et al. 2018 ("Monte Carlo
// methods for volumetric light transport simulation"): a homogeneous medium samples distances
// in closed form (one channel's exponential, weighted by the mixture of all three channels'
// densities, pbrt-v3's way), a grid samples them by delta tracking against the grid's majorant
// and estimates transmittance by ratio tracking (eq. 31 and 36 of that survey).
#include "common/math/vec.h"
#include "common/sampling/sampler.h"
#include "common/scene/scene_description.h"

namespace farm {

// Henyey and Greenstein 1941: p(cos) = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^{3/2}), with cos
// between the direction light travels before and after the scattering (g > 0: forward). Here
// as in the BSDFs both directions point away from the scattering point, so the cosine is
// -dot(wo, wi).
class HenyeyGreenstein {
 public:
  explicit HenyeyGreenstein(float g) : g_(g) {}
  float g() const { return g_; }
  // The density over the sphere of directions wi (equal to the phase function: sampling it is
  // exact, so a sample's weight is 1).
  float eval(const Vec3f& wo, const Vec3f& wi) const;
  Vec3f sample(const Vec3f& wo, const Vec2f& u, float* pdf) const;

 private:
  float g_;
};

// What sampleInteraction found along a segment: a scattering event at distance t (weight
// sigma_s T / p: the next path vertex lies in the medium) or none before the segment's end
// (weight T / p).
struct MediumInteraction {
  bool scattered = false;
  float t = 0;
  Spectrum weight{1.0f};
};

class Medium {
 public:
  explicit Medium(const MediumDescription& desc);

  const MediumDescription& description() const { return desc_; }
  HenyeyGreenstein phase() const { return HenyeyGreenstein(desc_.g); }
  bool isHomogeneous() const { return desc_.type == MediumDescription::Type::Homogeneous; }

  // Along o + t d (d of unit length), t in [0, tMax] (tMax may be infinite): samples the first
  // scattering event (a real collision that scatters), with numbers from `stream`. An unbiased
  // estimate in the sense that E[weight * f(next)] over the two outcomes is the volume
  // rendering equation's integral along the segment of sigma_s T f plus T at its end.
  MediumInteraction sampleInteraction(const Vec3f& o, const Vec3f& d, float tMax, Sampler& sampler,
                                      SampleStream stream) const;
  // The transmittance of the segment, exactly (homogeneous) or an unbiased non-negative
  // estimate by ratio tracking (grid), with numbers from `stream`.
  Spectrum transmittance(const Vec3f& o, const Vec3f& d, float tMax, Sampler& sampler,
                         SampleStream stream) const;
  // The same by ray marching, `steps` midpoint steps over the part of the segment in the grid
  // (a deterministic and biased quadrature, for a resolution fine enough to make its error
  // negligible).
  Spectrum marchedTransmittance(const Vec3f& o, const Vec3f& d, float tMax, int steps) const;

  // Path-space MLT's free flights: a proposal of distances whose density is known in closed
  // form (delta tracking's is the transmittance itself, which a grid does not give). A
  // homogeneous medium's exponential in one channel picked uniformly with uChannel (the same
  // mixture as sampleInteraction); in a grid, the exponential of a stepped optical depth: the
  // extinction at the midpoints of steps of half a cell along the ray's whole chord through
  // the grid's box (so that the steps are the same whichever end of the segment is sampled, and
  // close to delta tracking's distribution, where the majorant's exponential would almost never
  // pass a dense puff that the light does pass). Returns the distance of a vertex in [0, tMax),
  // or tMax when the flight passes the whole segment.
  float sampleFreeFlight(const Vec3f& o, const Vec3f& d, float tMax, float uChannel,
                         float uDistance) const;
  // Its density: of a vertex at distance tMax (lands), or the probability of passing the whole
  // segment [0, tMax].
  double freeFlightDensity(const Vec3f& o, const Vec3f& d, float tMax, bool lands) const;
  // sigma_s at p: the scattering coefficient a vertex in the medium contributes.
  Spectrum sigmaS(const Vec3f& p) const { return desc_.sigmaS * density(p); }

  // The grid's density at a world point (trilinear; 0 outside); 1 for a homogeneous medium.
  float density(const Vec3f& p) const;

 private:
  // The stepping of a free flight's chord through the grid's box (see sampleFreeFlight).
  struct FreeFlightChord {
    double t0 = 0, dt = 0;
    int steps = 0;
  };
  bool freeFlightChord(const Vec3f& o, const Vec3f& d, FreeFlightChord* chord) const;
  double chordSigma(const Vec3f& o, const Vec3f& d, const FreeFlightChord& chord, int i) const;
  // The part of the segment that lies in the grid's box, as [*t0, *t1]; false when none does.
  bool clipToGrid(const Vec3f& o, const Vec3f& d, float tMax, float* t0, float* t1) const;
  float value(int x, int y, int z) const;

  MediumDescription desc_;
  Spectrum sigmaT_;
  float majorant_ = 0;  // grid: the largest density times sigma_t (grey)
};

// Checks a description: finite non-negative coefficients, |g| < 1, a grid of the size it says
// with finite non-negative densities and a grey sigma_t. Returns the problem, or "" when none.
std::string mediumProblem(const MediumDescription& desc);

}  // namespace farm
