#include "common/scene/bsdf.h"

#include <stdexcept>

namespace farm {

namespace {

Vec3f mirror(const Vec3f& w) {
  return Vec3f(w.x, w.y, -w.z);
}

}  // namespace

Bsdf::Model Bsdf::makeModel(const BsdfDescription& desc) {
  using Type = BsdfDescription::Type;
  switch (desc.type) {
    case Type::Diffuse:
      return DiffuseBsdf(desc);
    case Type::Conductor:
      return SmoothConductorBsdf(desc);
    case Type::RoughConductor:
      return RoughConductorBsdf(desc);
    case Type::Dielectric:
      return SmoothDielectricBsdf(desc);
    case Type::RoughDielectric:
      return RoughDielectricBsdf(desc);
    case Type::Plastic:
      return PlasticBsdf(desc);
    case Type::CoatedDiffuse:
      return CoatedDiffuseBsdf(desc);
  }
  throw std::invalid_argument("unknown BSDF type");
}

Bsdf::Bsdf(const BsdfDescription& desc)
    : twoSided_(desc.twoSided),
      reflectanceTexture_(desc.reflectanceTexture),
      reflectance_(desc.reflectance),
      model_(makeModel(desc)) {
  if (desc.twoSided && (desc.type == BsdfDescription::Type::Dielectric ||
                        desc.type == BsdfDescription::Type::RoughDielectric))
    throw std::invalid_argument("a dielectric cannot be two-sided: its sides differ by nature");
}

void Bsdf::setReflectance(const Spectrum& reflectance) {
  reflectance_ = reflectance;
  std::visit([&](auto& model) { model.setReflectance(reflectance); }, model_);
}

bool Bsdf::smoothDielectricIndices(float* intIOR, float* extIOR) const {
  const SmoothDielectricBsdf* glass = std::get_if<SmoothDielectricBsdf>(&model_);
  if (!glass) return false;
  *intIOR = glass->intIOR();
  *extIOR = glass->extIOR();
  return true;
}

bool Bsdf::isBlack() const {
  return std::visit([](const auto& model) { return model.isBlack(); }, model_);
}

bool Bsdf::isDelta() const {
  return std::visit([](const auto& model) { return std::decay_t<decltype(model)>::kDelta; },
                    model_);
}

Spectrum Bsdf::eval(const Vec3f& wo, const Vec3f& wi, TransportMode mode) const {
  const bool back = mirrored(wo);
  return std::visit(
      [&](const auto& model) {
        return back ? model.eval(mirror(wo), mirror(wi), mode) : model.eval(wo, wi, mode);
      },
      model_);
}

float Bsdf::pdf(const Vec3f& wo, const Vec3f& wi) const {
  const bool back = mirrored(wo);
  return std::visit(
      [&](const auto& model) {
        return back ? model.pdf(mirror(wo), mirror(wi)) : model.pdf(wo, wi);
      },
      model_);
}

bool Bsdf::sample(const Vec3f& wo, const float u[3], TransportMode mode, BsdfSample* out) const {
  const bool back = mirrored(wo);
  const bool sampled = std::visit(
      [&](const auto& model) { return model.sample(back ? mirror(wo) : wo, u, mode, out); },
      model_);
  if (sampled && back) out->wi = mirror(out->wi);
  return sampled;
}

bool Bsdf::specularDirection(const Vec3f& wo, bool reflection, Vec3f* wi) const {
  const bool back = mirrored(wo);
  return std::visit(
      [&](const auto& model) {
        if constexpr (std::decay_t<decltype(model)>::kDelta) {
          if (!model.specularDirection(back ? mirror(wo) : wo, reflection, wi)) return false;
          if (back) *wi = mirror(*wi);
          return true;
        } else {
          return false;
        }
      },
      model_);
}

bool Bsdf::specularLobe(const Vec3f& wo, const Vec3f& wi, TransportMode mode, bool* reflection,
                        float* probability, Spectrum* value) const {
  const bool back = mirrored(wo);
  return std::visit(
      [&](const auto& model) {
        if constexpr (std::decay_t<decltype(model)>::kDelta) {
          return back ? model.specularLobe(mirror(wo), mirror(wi), mode, reflection, probability,
                                           value)
                      : model.specularLobe(wo, wi, mode, reflection, probability, value);
        } else {
          return false;
        }
      },
      model_);
}

float Bsdf::diracJacobian(const Vec3f& a, const Vec3f& b) const {
  return std::visit(
      [&](const auto& model) {
        if constexpr (std::decay_t<decltype(model)>::kDelta) {
          return model.diracJacobian(a, b);
        } else {
          return 1.0f;
        }
      },
      model_);
}

}  // namespace farm
