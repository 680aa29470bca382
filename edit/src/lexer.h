#pragma once
// The tokenizer of the edit language. Newlines are tokens (one statement per line); comments and
// blanks are dropped. UTF-8 spellings × ÷ ± are read as * / +-.
#include <string>
#include <vector>

#include "s2c/edit/script.h"

namespace s2c::edit {

enum class Tok { ident, number, string, symbol, newline, end };

struct Token {
  Tok kind = Tok::end;
  std::string text;  ///< ident / symbol spelling, string contents, number spelling
  double number = 0.0;
  Location at;
};

/// Human-readable description of a token for "found …" in messages.
std::string describe(const Token& t);

/// \throw ScriptError on an unknown character, an unterminated string or a malformed number.
std::vector<Token> tokenize(const std::string& text, const std::string& source);

}  // namespace s2c::edit
