#pragma once
// pbrt's scene grammar (pbrt-v3 and pbrt-v4), apart from what a scene means: the tokens
// (pbrt_tokenizer.h) become directives, each with its positional words and numbers and its
// parameter list of "type name" values, handed in file order to a PbrtTarget (pbrt_loader.cpp
// builds the scene from them), with Include and Import resolved here. After pbrt-v4's split of
// parser.cpp (the grammar, into a ParserTarget) from paramdict.cpp (typed parameters).
//
// Every error throws SceneLoadError (scene_files.h) naming the file and the line: a directive
// that does not parse, a parameter declared twice or of another type than asked, and, through
// rejectUnused(), every parameter no accessor read (an unknown one would otherwise change
// nothing, silently).
#include <initializer_list>
#include <string>
#include <vector>

namespace farm {

// One "type name" value parameter of a directive (pbrt's synonyms point, normal, vector and
// color read as point3, normal3, vector3 and rgb).
struct PbrtParam {
  std::string type, name;
  std::vector<double> numbers;
  std::vector<std::string> strings;  // strings, and bools as "true" / "false"
  int line = 0;
  bool used = false;  // read by an accessor
};

// A directive's words and values, with where it stands. The accessors mark what they read.
struct PbrtDirective {
  std::string name;
  std::vector<std::string> strings;  // positional strings
  std::vector<double> numbers;       // positional numbers
  std::vector<PbrtParam> params;
  std::string file;  // for messages: the file as the scene names it
  int line = 0;

  // The parameter called `name`, marked used; null when absent.
  PbrtParam* find(const std::string& name);
  bool has(const std::string& name) const;
  // find(), and an error unless its type is one of `types`.
  PbrtParam* typed(const std::string& name, std::initializer_list<const char*> types);
  // A parameter's value, or `def` when the directive does not give it.
  double getFloat(const std::string& name, double def);  // float or integer
  long long getInt(const std::string& name, long long def);
  bool getBool(const std::string& name, bool def);
  std::string getString(const std::string& name, const std::string& def);
  // A list of numbers whose count is a multiple of `multiple` (empty when absent).
  std::vector<double> getNumbers(const std::string& name, std::initializer_list<const char*> types,
                                 size_t multiple);

  [[noreturn]] void fail(const std::string& problem) const;
  [[noreturn]] void failParam(const PbrtParam& p, const std::string& problem) const;
  // Fails on the first parameter no accessor read: "<what>: parameter 'type name' is not
  // supported".
  void rejectUnused(const std::string& what) const;
};

// What the parser hands its directives to.
class PbrtTarget {
 public:
  virtual ~PbrtTarget() = default;
  // Every directive but Include and Import, in the order the files give them.
  virtual void directive(PbrtDirective& d) = 0;
  // An Include or Import, before the directives of the file it names.
  virtual void included(const PbrtDirective& d) { (void)d; }
};

// Parses the scene file at `path`, whose text is `text`, into `target`. Included files are read
// relative to the scene's folder, at most 16 deep and 1000 in all, and an include cycle is an
// error.
void parsePbrt(const std::string& path, const std::string& text, PbrtTarget* target);

}  // namespace farm
