#include "common/chain/algorithm.h"

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace farm {

namespace {

struct Named {
  Algorithm algorithm;
  const char* name;
};
constexpr Named kAlgorithms[] = {
    {Algorithm::PathTracing, "pt"}, {Algorithm::Bidirectional, "bdpt"},
    {Algorithm::PSSMLT, "pssmlt"},  {Algorithm::PSSMLTOverPT, "pssmlt-pt"},
    {Algorithm::MMLT, "mmlt"},      {Algorithm::MLT, "mlt"},
    {Algorithm::ERPT, "erpt"},
};

struct MixField {
  const char* name;
  double MutationMix::*weight;
};
constexpr MixField kMixFields[] = {
    {"bidir", &MutationMix::bidirectional},
    {"lens-subpath", &MutationMix::lensSubpath},
    {"lens", &MutationMix::lensPerturbation},
    {"caustic", &MutationMix::causticPerturbation},
    {"multichain", &MutationMix::multiChainPerturbation},
    {"manifold", &MutationMix::manifoldPerturbation},
};

}  // namespace

const char* algorithmName(Algorithm a) {
  for (const Named& n : kAlgorithms) {
    if (n.algorithm == a) return n.name;
  }
  return "?";
}

bool parseAlgorithm(const std::string& name, Algorithm* out) {
  for (const Named& n : kAlgorithms) {
    if (name == n.name) {
      *out = n.algorithm;
      return true;
    }
  }
  return false;
}

const char* algorithmList() {
  return "pt, bdpt, pssmlt, pssmlt-pt, mmlt, mlt or erpt";
}

std::vector<Algorithm> allAlgorithms() {
  std::vector<Algorithm> all;
  for (const Named& n : kAlgorithms) all.push_back(n.algorithm);
  return all;
}

bool MutationMix::operator==(const MutationMix& o) const {
  for (const MixField& f : kMixFields) {
    if (this->*f.weight != o.*f.weight) return false;
  }
  return true;
}

bool parseMutationMix(const std::string& text, MutationMix* out, std::string* error) {
  MutationMix mix = *out;
  std::istringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    size_t eq = item.find('=');
    std::string name = item.substr(0, eq);
    const MixField* field = nullptr;
    for (const MixField& f : kMixFields) {
      if (name == f.name) field = &f;
    }
    if (!field) {
      *error = "unknown mutation '" + name +
               "' (known: bidir, lens-subpath, lens, caustic, multichain, manifold)";
      return false;
    }
    if (eq == std::string::npos) {
      *error = "mutation '" + name + "' needs a weight, as in " + name + "=0.2";
      return false;
    }
    std::string value = item.substr(eq + 1);
    char* end = nullptr;
    double w = std::strtod(value.c_str(), &end);
    if (value.empty() || *end != '\0' || !std::isfinite(w) || w < 0) {
      *error =
          "weight of mutation '" + name + "' must be a finite number >= 0, not '" + value + "'";
      return false;
    }
    mix.*field->weight = w;
  }
  std::string problem = validateMutationMix(mix);
  if (!problem.empty()) {
    *error = problem;
    return false;
  }
  *out = mix;
  return true;
}

std::string formatMutationMix(const MutationMix& mix) {
  std::ostringstream s;
  s.precision(6);
  for (const MixField& f : kMixFields) {
    if (&f != kMixFields) s << ',';
    s << f.name << '=' << mix.*f.weight;
  }
  return s.str();
}

std::string validateMutationMix(const MutationMix& mix) {
  for (const MixField& f : kMixFields) {
    double w = mix.*f.weight;
    if (!std::isfinite(w) || w < 0)
      return std::string("mutation weight ") + f.name + " must be a finite number >= 0";
  }
  if (!(mix.bidirectional > 0))
    return "the bidirectional mutation's weight must be > 0: it is the one that reaches every "
           "path (the others only perturb)";
  return "";
}

}  // namespace farm
