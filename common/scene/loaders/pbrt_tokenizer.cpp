#include "common/scene/loaders/pbrt_tokenizer.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "common/scene/loaders/scene_files.h"

namespace farm {

namespace {
bool isNumberStart(char c) {
  return std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.';
}
bool isDelimiter(char c) {
  return std::isspace(static_cast<unsigned char>(c)) || c == '[' || c == ']' || c == '"' ||
         c == '#';
}
}  // namespace

std::vector<PbrtToken> tokenizePbrt(const std::string& text, const std::string& file) {
  std::vector<PbrtToken> tokens;
  int line = 1;
  size_t i = 0;
  const size_t n = text.size();
  while (i < n) {
    const char c = text[i];
    if (c == '\n') {
      ++line, ++i;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else if (c == '#') {
      while (i < n && text[i] != '\n') ++i;
    } else if (c == '[' || c == ']') {
      PbrtToken t;
      t.kind = c == '[' ? PbrtToken::Kind::OpenBracket : PbrtToken::Kind::CloseBracket;
      t.text = std::string(1, c);
      t.line = line;
      tokens.push_back(std::move(t));
      ++i;
    } else if (c == '"') {
      PbrtToken t;
      t.kind = PbrtToken::Kind::String;
      t.line = line;
      ++i;
      for (;;) {
        if (i >= n || text[i] == '\n')
          throw SceneLoadError(file, t.line, "unterminated string (a '\"' is missing)");
        char d = text[i++];
        if (d == '"') break;
        if (d == '\0') throw SceneLoadError(file, line, "a NUL character in a string");
        if (d == '\\') {
          if (i >= n) throw SceneLoadError(file, line, "unterminated string");
          char e = text[i++];
          switch (e) {
            case 'n':
              d = '\n';
              break;
            case 't':
              d = '\t';
              break;
            case '\\':
              d = '\\';
              break;
            case '"':
              d = '"';
              break;
            default:
              throw SceneLoadError(file, line,
                                   std::string("unknown escape '\\") + e + "' in a string");
          }
        }
        t.text.push_back(d);
      }
      tokens.push_back(std::move(t));
    } else {
      size_t start = i;
      while (i < n && !isDelimiter(text[i])) ++i;
      PbrtToken t;
      t.text = text.substr(start, i - start);
      t.line = line;
      if (isNumberStart(c)) {
        // from_chars takes no leading '+'.
        const char* first = t.text.data() + (c == '+' ? 1 : 0);
        const char* last = t.text.data() + t.text.size();
        auto [end, ec] = std::from_chars(first, last, t.number);
        if (ec != std::errc() || end != last || !std::isfinite(t.number))
          throw SceneLoadError(file, line, "'" + t.text + "' is not a finite number");
        // Everything ends up in float (positions, colours, scales): it must be finite there too.
        if (std::fabs(t.number) > double(std::numeric_limits<float>::max()))
          throw SceneLoadError(file, line, "'" + t.text + "' is beyond the range of float");
        t.kind = PbrtToken::Kind::Number;
      } else if (std::isalpha(static_cast<unsigned char>(c))) {
        for (char d : t.text)
          if (!std::isalnum(static_cast<unsigned char>(d)) && d != '_')
            throw SceneLoadError(file, line, "'" + t.text + "' is not a directive name");
        t.kind = PbrtToken::Kind::Word;
      } else {
        throw SceneLoadError(file, line, "unexpected character '" + std::string(1, c) + "'");
      }
      tokens.push_back(std::move(t));
    }
  }
  return tokens;
}

}  // namespace farm
