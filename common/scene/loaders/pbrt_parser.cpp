#include "common/scene/loaders/pbrt_parser.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "common/scene/loaders/pbrt_tokenizer.h"
#include "common/scene/loaders/scene_files.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

constexpr int kMaxIncludeDepth = 16;
constexpr int kMaxIncludedFiles = 1000;  // Include and Import directives in all

// How many positional words each directive takes before its parameter list (strings) or
// how many numbers; -1 for directives that are unknown here.
int positionalStrings(const std::string& name) {
  static const std::map<std::string, int> counts = {{"Shape", 1},
                                                    {"Material", 1},
                                                    {"MakeNamedMaterial", 1},
                                                    {"NamedMaterial", 1},
                                                    {"Texture", 3},
                                                    {"LightSource", 1},
                                                    {"AreaLightSource", 1},
                                                    {"Camera", 1},
                                                    {"Film", 1},
                                                    {"PixelFilter", 1},
                                                    {"Sampler", 1},
                                                    {"Integrator", 1},
                                                    {"Accelerator", 1},
                                                    {"Include", 1},
                                                    {"Import", 1},
                                                    {"CoordinateSystem", 1},
                                                    {"CoordSysTransform", 1},
                                                    {"MakeNamedMedium", 1},
                                                    {"ObjectBegin", 1},
                                                    {"ObjectInstance", 1},
                                                    {"ColorSpace", 1},
                                                    {"Attribute", 1},
                                                    {"Option", 0},
                                                    {"MediumInterface", -2},
                                                    {"ActiveTransform", -3}};
  auto it = counts.find(name);
  return it == counts.end() ? 0 : it->second;
}

void readArguments(const std::vector<PbrtToken>& tokens, size_t* i, PbrtDirective* d) {
  const std::string& name = d->name;
  auto atEnd = [&] { return *i >= tokens.size(); };
  int strings = positionalStrings(name);
  if (strings == -2) {  // MediumInterface: one or two strings
    while (!atEnd() && tokens[*i].kind == PbrtToken::Kind::String && d->strings.size() < 2)
      d->strings.push_back(tokens[(*i)++].text);
    return;
  }
  if (strings == -3) {  // ActiveTransform StartTime | EndTime | All
    if (atEnd() || tokens[*i].kind != PbrtToken::Kind::Word)
      d->fail("ActiveTransform takes StartTime, EndTime or All");
    d->strings.push_back(tokens[(*i)++].text);
    return;
  }
  for (int k = 0; k < strings; ++k) {
    if (atEnd() || tokens[*i].kind != PbrtToken::Kind::String)
      d->fail(name + " expects " + std::to_string(strings) + " quoted string" +
              (strings > 1 ? "s" : "") + " first");
    d->strings.push_back(tokens[(*i)++].text);
  }
  // Bare or bracketed numbers (Translate 1 2 3, Transform [ ... ]).
  if (!atEnd() && tokens[*i].kind == PbrtToken::Kind::OpenBracket && strings == 0 &&
      name != "Option") {
    ++*i;
    while (!atEnd() && tokens[*i].kind == PbrtToken::Kind::Number)
      d->numbers.push_back(tokens[(*i)++].number);
    if (atEnd() || tokens[*i].kind != PbrtToken::Kind::CloseBracket)
      d->fail("expected ']' closing the numbers of " + name);
    ++*i;
  }
  while (!atEnd() && tokens[*i].kind == PbrtToken::Kind::Number)
    d->numbers.push_back(tokens[(*i)++].number);
  // The parameter list: "type name" value pairs.
  std::set<std::string> names;
  while (!atEnd() && tokens[*i].kind == PbrtToken::Kind::String) {
    const PbrtToken& decl = tokens[(*i)++];
    PbrtParam p;
    p.line = decl.line;
    std::string text = decl.text;
    size_t a = text.find_first_not_of(" \t");
    size_t sp = text.find_first_of(" \t", a);
    size_t b = sp == std::string::npos ? sp : text.find_first_not_of(" \t", sp);
    if (a == std::string::npos || sp == std::string::npos || b == std::string::npos)
      throw SceneLoadError(d->file, decl.line,
                           "'" + text + "' is not a parameter declaration (\"type name\")");
    p.type = text.substr(a, sp - a);
    size_t e = text.find_last_not_of(" \t");
    p.name = text.substr(b, e - b + 1);
    if (p.name.find_first_of(" \t") != std::string::npos)
      throw SceneLoadError(d->file, decl.line,
                           "'" + text + "' is not a parameter declaration (\"type name\")");
    if (p.type == "point") p.type = "point3";
    if (p.type == "normal") p.type = "normal3";
    if (p.type == "vector") p.type = "vector3";
    if (p.type == "color") p.type = "rgb";
    auto readValue = [&](const PbrtToken& v) {
      if (v.kind == PbrtToken::Kind::Number) {
        p.numbers.push_back(v.number);
      } else if (v.kind == PbrtToken::Kind::String ||
                 (v.kind == PbrtToken::Kind::Word && (v.text == "true" || v.text == "false"))) {
        p.strings.push_back(v.text);
      } else {
        throw SceneLoadError(d->file, v.line,
                             "unexpected '" + v.text + "' in the value of '" + p.name + "'");
      }
    };
    if (atEnd())
      throw SceneLoadError(d->file, decl.line, "parameter '" + p.name + "' has no value");
    if (tokens[*i].kind == PbrtToken::Kind::OpenBracket) {
      ++*i;
      while (!atEnd() && tokens[*i].kind != PbrtToken::Kind::CloseBracket)
        readValue(tokens[(*i)++]);
      if (atEnd())
        throw SceneLoadError(d->file, decl.line, "expected ']' closing '" + p.name + "'");
      ++*i;
    } else {
      readValue(tokens[(*i)++]);
    }
    if (!p.numbers.empty() && !p.strings.empty())
      throw SceneLoadError(d->file, p.line, "parameter '" + p.name + "' mixes numbers and strings");
    if (!names.insert(p.name).second)
      throw SceneLoadError(d->file, p.line, "parameter '" + p.name + "' given twice");
    d->params.push_back(std::move(p));
  }
}

// The files of one scene: its folder, which includes are open, how many were read.
class Parser {
 public:
  Parser(const std::string& path, PbrtTarget* target)
      : dir_(fs::path(path).parent_path()), target_(target) {
    includeStack_.push_back(fs::absolute(path).lexically_normal().string());
  }

  void parse(const std::string& text, const std::string& file, int depth) {
    const std::vector<PbrtToken> tokens = tokenizePbrt(text, file);
    size_t i = 0;
    while (i < tokens.size()) {
      const PbrtToken& t = tokens[i];
      if (t.kind != PbrtToken::Kind::Word)
        throw SceneLoadError(file, t.line, "expected a directive, found '" + t.text + "'");
      PbrtDirective d;
      d.name = t.text;
      d.file = file;
      d.line = t.line;
      ++i;
      readArguments(tokens, &i, &d);
      if (d.name == "Include" || d.name == "Import") {
        if (d.strings.size() != 1) d.fail(d.name + " takes one file name");
        if (depth + 1 > kMaxIncludeDepth)
          d.fail(d.name + " nested deeper than " + std::to_string(kMaxIncludeDepth) + " files");
        if (++includedFiles_ > kMaxIncludedFiles)
          d.fail("more than " + std::to_string(kMaxIncludedFiles) + " included files");
        fs::path included = sceneFilePath(dir_, d.strings[0], "included file", d.file, d.line);
        const std::string key = fs::absolute(included).lexically_normal().string();
        if (std::find(includeStack_.begin(), includeStack_.end(), key) != includeStack_.end())
          d.fail(d.name + " of '" + d.strings[0] + "' includes itself (an include cycle)");
        includeStack_.push_back(key);
        target_->included(d);
        parse(readSceneFile(included, "'" + d.strings[0] + "'", d.file, d.line),
              (dir_ / d.strings[0]).string(), depth + 1);
        includeStack_.pop_back();
        continue;
      }
      target_->directive(d);
    }
  }

 private:
  fs::path dir_;
  PbrtTarget* target_;
  int includedFiles_ = 0;
  std::vector<std::string> includeStack_;
};

}  // namespace

void parsePbrt(const std::string& path, const std::string& text, PbrtTarget* target) {
  Parser(path, target).parse(text, path, 0);
}

PbrtParam* PbrtDirective::find(const std::string& name) {
  for (PbrtParam& p : params)
    if (p.name == name) {
      p.used = true;
      return &p;
    }
  return nullptr;
}

bool PbrtDirective::has(const std::string& name) const {
  for (const PbrtParam& p : params)
    if (p.name == name) return true;
  return false;
}

void PbrtDirective::fail(const std::string& problem) const {
  throw SceneLoadError(file, line, problem);
}

void PbrtDirective::failParam(const PbrtParam& p, const std::string& problem) const {
  throw SceneLoadError(file, p.line ? p.line : line, problem);
}

void PbrtDirective::rejectUnused(const std::string& what) const {
  for (const PbrtParam& p : params)
    if (!p.used)
      failParam(p, what + ": parameter '" + p.type + " " + p.name + "' is not supported");
}

PbrtParam* PbrtDirective::typed(const std::string& name, std::initializer_list<const char*> types) {
  PbrtParam* p = find(name);
  if (!p) return nullptr;
  for (const char* t : types)
    if (p->type == t) return p;
  std::string allowed;
  for (const char* t : types) allowed += (allowed.empty() ? "" : " or ") + std::string(t);
  failParam(*p, "parameter '" + name + "' must be of type " + allowed + ", not " + p->type);
}

double PbrtDirective::getFloat(const std::string& name, double def) {
  PbrtParam* p = typed(name, {"float", "integer"});
  if (!p) return def;
  if (p->numbers.size() != 1) failParam(*p, "parameter '" + name + "' takes one number");
  return p->numbers[0];
}

long long PbrtDirective::getInt(const std::string& name, long long def) {
  PbrtParam* p = typed(name, {"integer"});
  if (!p) return def;
  if (p->numbers.size() != 1) failParam(*p, "parameter '" + name + "' takes one integer");
  double v = p->numbers[0];
  if (v != std::floor(v) || std::fabs(v) > 1e15)
    failParam(*p, "parameter '" + name + "' is not an integer");
  return (long long)v;
}

bool PbrtDirective::getBool(const std::string& name, bool def) {
  PbrtParam* p = typed(name, {"bool"});
  if (!p) return def;
  if (p->strings.size() != 1 || (p->strings[0] != "true" && p->strings[0] != "false"))
    failParam(*p, "parameter '" + name + "' must be true or false");
  return p->strings[0] == "true";
}

std::string PbrtDirective::getString(const std::string& name, const std::string& def) {
  PbrtParam* p = typed(name, {"string"});
  if (!p) return def;
  if (p->strings.size() != 1) failParam(*p, "parameter '" + name + "' takes one string");
  return p->strings[0];
}

std::vector<double> PbrtDirective::getNumbers(const std::string& name,
                                              std::initializer_list<const char*> types,
                                              size_t multiple) {
  PbrtParam* p = typed(name, types);
  if (!p) return {};
  if (!p->strings.empty() || p->numbers.size() % multiple != 0)
    failParam(*p, "parameter '" + name + "' needs a multiple of " + std::to_string(multiple) +
                      " numbers");
  return p->numbers;
}

}  // namespace farm
