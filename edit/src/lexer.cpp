#include "lexer.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include <fmt/format.h>

namespace s2c::edit {

ScriptError::ScriptError(const std::string& source, Location where, const std::string& what)
    : InvalidInput(fmt::format("{}:{}:{}: {}", source, where.line, where.column, what)), at(where) {}

std::string describe(const Token& t) {
  switch (t.kind) {
    case Tok::ident: return fmt::format("'{}'", t.text);
    case Tok::number: return fmt::format("number {}", t.text);
    case Tok::string: return fmt::format("string \"{}\"", t.text);
    case Tok::symbol: return fmt::format("'{}'", t.text);
    case Tok::newline: return "end of line";
    case Tok::end: return "end of script";
  }
  return "?";
}

namespace {

// Symbols, longest first so "<=" wins over "<".
const char* const kSymbols[] = {"+-", "<=", ">=", "==", "||", "+", "-", "*", "/", "(", ")", "[", "]",
                                ",", ".", "=", "~", "<", ">"};
// UTF-8 spellings and what they mean.
const std::pair<const char*, const char*> kUnicode[] = {{"\xC3\x97", "*"}, {"\xC3\xB7", "/"}, {"\xC2\xB1", "+-"},
                                                        {"\xE2\x88\x92", "-"}, {"\xE2\x89\xA4", "<="},
                                                        {"\xE2\x89\xA5", ">="}};

bool starts_with(const std::string& s, std::size_t i, const char* p) { return s.compare(i, std::strlen(p), p) == 0; }

}  // namespace

std::vector<Token> tokenize(const std::string& text, const std::string& source) {
  std::vector<Token> out;
  int line = 1;
  std::size_t line_start = 0;
  std::size_t i = 0;
  // Columns count characters, not bytes (UTF-8 continuation bytes are skipped); counted on from
  // the last position asked for, so a long line costs its length once.
  std::size_t counted = 0;
  int column = 1;
  auto here = [&] {
    if (counted < line_start) {
      counted = line_start;
      column = 1;
    }
    for (; counted < i; ++counted) column += (static_cast<unsigned char>(text[counted]) & 0xC0) != 0x80;
    return Location{line, column};
  };
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n') {
      out.push_back({Tok::newline, "\n", 0.0, here()});
      ++i;
      ++line;
      line_start = i;
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r') {
      ++i;
      continue;
    }
    if (c == '#') {
      while (i < text.size() && text[i] != '\n') ++i;
      continue;
    }
    const Location at = here();
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      std::size_t j = i;
      while (j < text.size() && (std::isalnum(static_cast<unsigned char>(text[j])) || text[j] == '_')) ++j;
      out.push_back({Tok::ident, text.substr(i, j - i), 0.0, at});
      i = j;
      continue;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) ||
        (c == '.' && i + 1 < text.size() && std::isdigit(static_cast<unsigned char>(text[i + 1])))) {
      // strtod would also take "1e" tails and hex; accept digits, one '.', and an exponent only.
      std::size_t j = i;
      while (j < text.size() && std::isdigit(static_cast<unsigned char>(text[j]))) ++j;
      if (j < text.size() && text[j] == '.') {
        ++j;
        while (j < text.size() && std::isdigit(static_cast<unsigned char>(text[j]))) ++j;
      }
      if (j < text.size() && (text[j] == 'e' || text[j] == 'E')) {
        std::size_t k = j + 1;
        if (k < text.size() && (text[k] == '+' || text[k] == '-')) ++k;
        if (k < text.size() && std::isdigit(static_cast<unsigned char>(text[k]))) {
          while (k < text.size() && std::isdigit(static_cast<unsigned char>(text[k]))) ++k;
          j = k;
        }
      }
      const std::string spelling = text.substr(i, j - i);
      const double v = std::strtod(spelling.c_str(), nullptr);
      if (!std::isfinite(v)) throw ScriptError(source, at, fmt::format("number {} is out of range", spelling));
      out.push_back({Tok::number, spelling, v, at});
      i = j;
      continue;
    }
    if (c == '"') {
      std::size_t j = i + 1;
      while (j < text.size() && text[j] != '"' && text[j] != '\n') ++j;
      if (j >= text.size() || text[j] != '"') throw ScriptError(source, at, "unterminated string: expected '\"' before the end of the line");
      out.push_back({Tok::string, text.substr(i + 1, j - i - 1), 0.0, at});
      i = j + 1;
      continue;
    }
    bool matched = false;
    for (const auto& [utf8, meaning] : kUnicode)
      if (starts_with(text, i, utf8)) {
        out.push_back({Tok::symbol, meaning, 0.0, at});
        i += std::strlen(utf8);
        matched = true;
        break;
      }
    if (matched) continue;
    for (const char* s : kSymbols)
      if (starts_with(text, i, s)) {
        out.push_back({Tok::symbol, s, 0.0, at});
        i += std::strlen(s);
        matched = true;
        break;
      }
    if (matched) continue;
    const unsigned char u = static_cast<unsigned char>(c);
    throw ScriptError(source, at,
                      u < 0x20 || u >= 0x7f ? fmt::format("unexpected byte 0x{:02x}", u)
                                            : fmt::format("unexpected character '{}'", c));
  }
  out.push_back({Tok::newline, "\n", 0.0, here()});
  out.push_back({Tok::end, "", 0.0, here()});
  return out;
}

}  // namespace s2c::edit
