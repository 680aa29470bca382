// Recursive-descent parser of the edit language (grammar in s2c/edit/script.h). Every error names
// the line and column, what was expected and what was found.
#include <algorithm>
#include <cmath>
#include <set>

#include <fmt/format.h>

#include "lexer.h"

namespace s2c::edit {

const std::vector<std::string>& constraint_names() {
  static const std::vector<std::string> names = {"equal_length", "connected",     "collinear",   "parallel",
                                                 "concentric",   "coaxial",       "perpendicular", "fixed_angle",
                                                 "equal_angle",  "symmetric",     "equal_radius"};
  return names;
}

namespace {

const std::set<std::string> kTypes = {"plane", "cylinder", "sphere", "cone",  "line",
                                      "circle", "arc",     "freeform", "patch", "curve", "feature"};
const std::set<std::string> kNumericProps = {"radius", "area", "length", "half_angle", "count"};
const std::set<std::string> kKeywords = {"param", "let", "vertex",    "select", "where",       "set",    "move",   "rotate",
                                         "scale", "constrain", "unconstrain", "lock", "assert", "export", "by",
                                         "about", "at",     "and",    "or",          "not",    "adjacent", "to"};

// Nesting deeper than this (parentheses, brackets, unary operators, `not`) is refused: the
// parser, the interpreter and the tree's destructor all recurse over it.
constexpr int kMaxDepth = 256;
// Terms in one chain of + - * / or and / or: a chain is a left-deep tree.
constexpr int kMaxChain = 4096;

class Parser {
 public:
  Parser(std::vector<Token> tokens, const std::string& text, std::string source)
      : t_(std::move(tokens)), text_(text), source_(std::move(source)) {}

  // One expression and nothing after it (--set values).
  ExprPtr whole_expression() {
    ExprPtr e = expr();
    if (peek().kind != Tok::newline && peek().kind != Tok::end) fail("end of the value");
    return e;
  }

  Script script() {
    Script s;
    s.source = source_;
    bool seen_other = false;
    while (peek().kind != Tok::end) {
      if (peek().kind == Tok::newline) {
        ++i_;
        continue;
      }
      Statement st = statement();
      if (st.kind == Statement::Kind::param) {
        if (seen_other)
          throw ScriptError(source_, st.at, "'param' must come before every other statement (parameters are set at the top)");
      } else {
        seen_other = true;
      }
      expect_end_of_line();
      s.statements.push_back(std::move(st));
    }
    return s;
  }

 private:
  const Token& peek(int k = 0) const { return t_[std::min(i_ + k, t_.size() - 1)]; }
  const Token& next() { return t_[std::min(i_++, t_.size() - 1)]; }
  bool is_symbol(const char* s, int k = 0) const { return peek(k).kind == Tok::symbol && peek(k).text == s; }
  bool is_word(const char* w, int k = 0) const { return peek(k).kind == Tok::ident && peek(k).text == w; }

  [[noreturn]] void fail(const std::string& expected) const {
    throw ScriptError(source_, peek().at, fmt::format("expected {}, found {}", expected, describe(peek())));
  }
  void expect_symbol(const char* s) {
    if (!is_symbol(s)) fail(fmt::format("'{}'", s));
    ++i_;
  }
  void expect_word(const char* w) {
    if (!is_word(w)) fail(fmt::format("'{}'", w));
    ++i_;
  }
  void expect_end_of_line() {
    if (peek().kind != Tok::newline && peek().kind != Tok::end) fail("end of line");
    ++i_;
  }
  // A user name (selection, parameter): an identifier that is not a keyword.
  std::string name(const char* what) {
    if (peek().kind != Tok::ident || kKeywords.count(peek().text)) fail(what);
    return next().text;
  }

  std::string line_text(int line) const {
    std::size_t start = 0;
    for (int l = 1; l < line && start != std::string::npos; ++l) {
      start = text_.find('\n', start);
      if (start != std::string::npos) ++start;
    }
    if (start == std::string::npos) return {};
    std::string s = text_.substr(start, text_.find('\n', start) - start);
    if (auto h = s.find('#'); h != std::string::npos) s.erase(h);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
    s.erase(0, s.find_first_not_of(" \t"));
    return s;
  }

  Statement statement() {
    Statement st;
    st.at = peek().at;
    st.text = line_text(st.at.line);
    if (peek().kind != Tok::ident)
      fail("a statement (param, let, set, move, rotate, scale, constrain, unconstrain, lock, assert, export)");
    const std::string word = next().text;
    if (word == "param") {
      st.kind = Statement::Kind::param;
      st.name_at = peek().at;
      st.name = name("a parameter name");
      expect_symbol("=");
      st.value = expr();
    } else if (word == "let") {
      st.name_at = peek().at;
      st.name = name("a name for the selection");
      expect_symbol("=");
      if (is_word("select")) {
        ++i_;
        st.kind = Statement::Kind::let_select;
        st.selector = selector();
      } else {
        st.kind = Statement::Kind::let_value;
        st.value = expr();
      }
    } else if (word == "set") {
      st.kind = Statement::Kind::set;
      st.name_at = peek().at;
      st.name = name("a selection name");
      expect_symbol(".");
      if (!is_word("radius") && !is_word("half_angle")) fail("'radius' or 'half_angle'");
      st.property = next().text;
      expect_symbol("=");
      st.value = expr();
    } else if (word == "move" && is_word("vertex")) {
      // A low-level edit: the vertex moves, the patches holding it follow (bubbling, paper §4.1).
      ++i_;
      st.kind = Statement::Kind::move_vertex;
      st.axis = expr();  // the vertex index
      expect_word("by");
      st.value = expr();
    } else if (word == "move") {
      st.kind = Statement::Kind::move;
      st.name_at = peek().at;
      st.name = name("a selection name");
      expect_word("by");
      st.value = expr();
    } else if (word == "rotate") {
      st.kind = Statement::Kind::rotate;
      st.name_at = peek().at;
      st.name = name("a selection name");
      expect_word("about");
      st.axis = direction_expr();
      expect_word("by");
      st.value = expr();
      if (is_word("at")) {
        ++i_;
        st.pivot = expr();
      }
    } else if (word == "scale") {
      st.kind = Statement::Kind::scale;
      st.name_at = peek().at;
      st.name = name("a selection name");
      expect_word("by");
      st.value = expr();
      if (is_word("at")) {
        ++i_;
        st.pivot = expr();
      }
    } else if (word == "constrain" || word == "unconstrain") {
      st.kind = word == "constrain" ? Statement::Kind::constrain : Statement::Kind::unconstrain;
      if (word == "unconstrain" && peek().kind == Tok::ident && !is_symbol("(", 1)) {
        st.name_at = peek().at;
      st.name = name("a constraint kind or a selection name");
      } else {
        constraint_call(st);
        if (word == "constrain" && is_symbol("=")) {
          ++i_;
          st.value = expr();
        }
      }
    } else if (word == "lock") {
      st.kind = Statement::Kind::lock;
      st.name_at = peek().at;
      st.name = name("a selection name");
    } else if (word == "assert") {
      st.kind = Statement::Kind::check;
      if (peek().kind == Tok::ident && is_symbol("(", 1)) {
        constraint_call(st);
        if (is_symbol("=")) {  // fixed_angle / equal_angle: the angle that must hold
          ++i_;
          st.value = expr();
        }
      } else {
        st.name_at = peek().at;
      st.name = name("a selection name or a constraint kind");
        expect_symbol(".");
        st.condition = property_condition();
        st.property = st.condition->property;
      }
    } else if (word == "export") {
      st.kind = Statement::Kind::export_mesh;
      if (peek().kind != Tok::string) fail("a quoted file name");
      st.path = next().text;
      if (st.path.empty()) throw ScriptError(source_, st.at, "export needs a file name");
    } else {
      throw ScriptError(source_, st.at,
                        fmt::format("unknown statement '{}': expected param, let, set, move, rotate, scale, "
                                    "constrain, unconstrain, lock, assert or export",
                                    word));
    }
    return st;
  }

  void constraint_call(Statement& st) {
    const Token& k = peek();
    if (k.kind != Tok::ident) fail("a constraint kind");
    const auto& kinds = constraint_names();
    if (std::find(kinds.begin(), kinds.end(), k.text) == kinds.end())
      throw ScriptError(source_, k.at,
                        fmt::format("unknown constraint kind '{}': expected one of {}", k.text, fmt::join(kinds, ", ")));
    st.constraint = next().text;
    expect_symbol("(");
    do {
      st.member_at.push_back(peek().at);
      st.members.push_back(name("a selection name"));
      if (!is_symbol(",")) break;
      ++i_;
    } while (true);
    expect_symbol(")");
  }

  Selector selector() {
    Selector s;
    if (peek().kind != Tok::ident) fail("a feature type (plane, cylinder, sphere, cone, line, circle, arc, freeform, patch, curve, feature)");
    std::string type = peek().text;
    if (!kTypes.count(type) && type.size() > 1 && type.back() == 's' && kTypes.count(type.substr(0, type.size() - 1)))
      type.pop_back();
    if (!kTypes.count(type)) fail("a feature type (plane, cylinder, sphere, cone, line, circle, arc, freeform, patch, curve, feature)");
    ++i_;
    s.type = type;
    if (is_word("where")) {
      ++i_;
      s.where = condition();
    }
    if (peek().kind == Tok::ident) {
      const std::string w = peek().text;
      if (w == "highest" || w == "lowest") {
        ++i_;
        s.picker = w == "highest" ? Picker::highest : Picker::lowest;
        if (is_word("along")) {
          ++i_;
          s.picker_arg = direction_expr();
        }
      } else if (w == "largest" || w == "smallest") {
        ++i_;
        s.picker = w == "largest" ? Picker::largest : Picker::smallest;
      } else if (w == "nearest") {
        ++i_;
        s.picker = Picker::nearest;
        s.picker_arg = expr();
      } else {
        fail("'where', a picker (highest, lowest, largest, smallest, nearest) or end of line");
      }
    }
    return s;
  }

  ConditionPtr condition() {
    Deeper guard(*this);
    return chain("or", Condition::Kind::any_of, &Parser::conjunction);
  }
  ConditionPtr conjunction() { return chain("and", Condition::Kind::all_of, &Parser::unary_condition); }
  // OPERAND (WORD OPERAND)*: one node holding every operand, or the operand alone.
  ConditionPtr chain(const char* word, Condition::Kind kind, ConditionPtr (Parser::*operand)()) {
    ConditionPtr left = (this->*operand)();
    if (!is_word(word)) return left;
    auto c = std::make_shared<Condition>();
    c->kind = kind;
    c->at = left->at;
    c->children.push_back(left);
    int n = 0;
    while (is_word(word)) {
      ++i_;
      count_chain(n);
      c->children.push_back((this->*operand)());
    }
    return c;
  }
  ConditionPtr unary_condition() {
    Deeper guard(*this);
    if (is_word("not")) {
      auto c = std::make_shared<Condition>();
      c->kind = Condition::Kind::negate;
      c->at = next().at;
      c->children.push_back(unary_condition());
      return c;
    }
    if (is_symbol("(")) {
      ++i_;
      ConditionPtr c = condition();
      expect_symbol(")");
      return c;
    }
    if (is_word("adjacent")) {
      auto c = std::make_shared<Condition>();
      c->kind = Condition::Kind::adjacent;
      c->at = next().at;
      expect_word("to");
      c->name = name("a selection name");
      return c;
    }
    return property_condition();
  }

  // PROP OP EXPR | PROP ~ EXPR [+- EXPR] | normal/axis ~ DIR [+- DEG] | axis || DIR | center ~ VEC +- EXPR
  ConditionPtr property_condition() {
    auto c = std::make_shared<Condition>();
    c->at = peek().at;
    if (peek().kind != Tok::ident) fail("a property (radius, area, length, half_angle, count, normal, axis, center)");
    const std::string prop = next().text;
    c->property = prop;
    if (prop == "normal" || prop == "axis") {
      if (prop == "axis" && is_symbol("||")) {
        ++i_;
        c->kind = Condition::Kind::parallel_axis;
        c->value = direction_expr();
      } else {
        expect_symbol("~");
        c->kind = Condition::Kind::direction;
        c->value = direction_expr();
      }
      if (is_symbol("+-")) {
        ++i_;
        c->tolerance = expr();
      }
      return c;
    }
    if (prop == "center") {
      expect_symbol("~");
      c->kind = Condition::Kind::near_point;
      c->value = expr();
      expect_symbol("+-");
      c->tolerance = expr();
      return c;
    }
    if (!kNumericProps.count(prop))
      throw ScriptError(source_, c->at,
                        fmt::format("unknown property '{}': expected radius, area, length, half_angle, count, normal, "
                                    "axis or center",
                                    prop));
    if (is_symbol("~")) {
      ++i_;
      c->kind = Condition::Kind::approx;
      c->value = expr();
      if (is_symbol("+-")) {
        ++i_;
        c->tolerance = expr();
      }
      return c;
    }
    for (const char* op : {"<=", ">=", "==", "<", ">"})
      if (is_symbol(op)) {
        ++i_;
        c->kind = Condition::Kind::compare;
        c->op = op;
        c->value = expr();
        return c;
      }
    fail("a comparison (<, <=, >, >=, ==, ~)");
  }

  // ±x ±y ±z, or any vector expression.
  ExprPtr direction_expr() {
    int k = 0;
    double sign = 1.0;
    if (is_symbol("+") || is_symbol("-")) {
      sign = is_symbol("-") ? -1.0 : 1.0;
      k = 1;
    }
    if (peek(k).kind == Tok::ident && (peek(k).text == "x" || peek(k).text == "y" || peek(k).text == "z") &&
        !is_symbol(".", k + 1)) {
      auto e = std::make_shared<Expr>();
      e->kind = Expr::Kind::vector;
      e->at = peek().at;
      const int axis = peek(k).text[0] - 'x';
      for (int a = 0; a < 3; ++a) {
        auto n = std::make_shared<Expr>();
        n->kind = Expr::Kind::number;
        n->at = e->at;
        n->number = a == axis ? sign : 0.0;
        e->args.push_back(n);
      }
      i_ += k + 1;
      return e;
    }
    return expr();
  }

  ExprPtr binary(char op, ExprPtr a, ExprPtr b, Location at) {
    auto e = std::make_shared<Expr>();
    e->kind = Expr::Kind::binary;
    e->at = at;  // errors of the operation (division by zero, vector × vector) point at the operator
    e->op = op;
    e->args = {std::move(a), std::move(b)};
    return e;
  }
  ExprPtr expr() {
    Deeper guard(*this);
    ExprPtr e = term();
    int n = 0;
    while (is_symbol("+") || is_symbol("-")) {
      count_chain(n);
      const Token& op = next();
      e = binary(op.text[0], e, term(), op.at);
    }
    return e;
  }
  ExprPtr term() {
    ExprPtr e = factor();
    int n = 0;
    while (is_symbol("*") || is_symbol("/")) {
      count_chain(n);
      const Token& op = next();
      e = binary(op.text[0], e, factor(), op.at);
    }
    return e;
  }
  ExprPtr factor() {
    Deeper guard(*this);
    if (is_symbol("-") || is_symbol("+")) {
      const Token& t = next();
      ExprPtr inner = factor();
      if (t.text == "+") return inner;
      auto e = std::make_shared<Expr>();
      e->kind = Expr::Kind::negate;
      e->at = t.at;
      e->args.push_back(inner);
      return e;
    }
    ExprPtr e = primary();
    // Unit suffixes: mm and deg are the language's units; rad converts.
    if (is_word("mm") || is_word("deg")) {
      ++i_;
    } else if (is_word("rad")) {
      auto k = std::make_shared<Expr>();
      k->kind = Expr::Kind::number;
      k->at = next().at;
      k->number = 180.0 / M_PI;
      e = binary('*', e, k, k->at);
    }
    return e;
  }
  ExprPtr primary() {
    auto e = std::make_shared<Expr>();
    e->at = peek().at;
    if (peek().kind == Tok::number) {
      e->kind = Expr::Kind::number;
      e->number = next().number;
      return e;
    }
    if (is_symbol("(")) {
      ++i_;
      ExprPtr inner = expr();
      expect_symbol(")");
      return inner;
    }
    if (is_symbol("[")) {
      ++i_;
      e->kind = Expr::Kind::vector;
      for (int a = 0; a < 3; ++a) {
        if (a > 0) expect_symbol(",");
        e->args.push_back(expr());
      }
      if (is_symbol(",")) throw ScriptError(source_, peek().at, "a vector has 3 components: expected ']', found ','");
      expect_symbol("]");
      return e;
    }
    if (peek().kind == Tok::ident && !kKeywords.count(peek().text)) {
      e->name = next().text;
      e->kind = Expr::Kind::name;
      if (is_symbol(".")) {
        ++i_;
        if (peek().kind != Tok::ident) fail("a property name");
        e->kind = Expr::Kind::property;
        e->property = next().text;
      }
      return e;
    }
    fail("a number, a name, '[' or '('");
  }

  struct Deeper {
    Parser& p;
    explicit Deeper(Parser& parser) : p(parser) {
      if (++p.depth_ > kMaxDepth)
        throw ScriptError(p.source_, p.peek().at, fmt::format("nested more than {} levels deep", kMaxDepth));
    }
    ~Deeper() { --p.depth_; }
  };
  void count_chain(int& n) const {
    if (++n > kMaxChain) throw ScriptError(source_, peek().at, fmt::format("more than {} terms in one expression", kMaxChain));
  }

  std::vector<Token> t_;
  std::size_t i_ = 0;
  int depth_ = 0;
  const std::string& text_;
  std::string source_;
};

}  // namespace

Script parse_script(const std::string& text, const std::string& source) {
  Parser p(tokenize(text, source), text, source);
  return p.script();
}

ExprPtr parse_expression(const std::string& text, const std::string& source) {
  Parser p(tokenize(text, source), text, source);
  return p.whole_expression();
}

}  // namespace s2c::edit
