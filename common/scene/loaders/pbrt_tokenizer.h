#pragma once
// The tokens of a pbrt-v3 or pbrt-v4 scene file: directive names and other bare words, quoted
// strings, numbers and brackets, each with its line; '#' comments run to the end of the line.
#include <string>
#include <vector>

namespace farm {

struct PbrtToken {
  enum class Kind { Word, String, Number, OpenBracket, CloseBracket };
  Kind kind = Kind::Word;
  std::string text;   // the word, or the string without its quotes and with escapes resolved
  double number = 0;  // Number
  int line = 0;
};

// Throws SceneLoadError (scene_files.h) naming `file` and the line for an unterminated string,
// an unknown escape, a malformed or non-finite number, or a stray character.
std::vector<PbrtToken> tokenizePbrt(const std::string& text, const std::string& file);

}  // namespace farm
