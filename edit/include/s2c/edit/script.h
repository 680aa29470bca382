#pragma once
/// \file The edit language (.s2e, DESIGN.md "The edit language"): its syntax tree and parser.
/// One statement per line; '#' starts a comment; lengths in mm, angles in degrees.
///
///   param NAME = EXPR                       (only before other statements; --set NAME=VALUE overrides)
///   let NAME = select TYPE [where COND] [PICKER]   |   let NAME = EXPR
///   set NAME.radius|half_angle = EXPR
///   move NAME by VEC
///   move vertex INDEX by VEC              (low-level: the patches holding the vertex follow)
///   rotate NAME about VEC by EXPR [deg] [at VEC]
///   scale NAME by EXPR [at VEC]
///   constrain KIND(NAME, NAME[, ...]) [= EXPR]
///   unconstrain KIND(NAME, NAME[, ...])  |  unconstrain NAME
///   lock NAME
///   assert NAME.PROP COND-TAIL  |  assert KIND(NAME, NAME[, ...]) [= EXPR]
///   export "PATH"
///
/// TYPE: plane cylinder sphere cone line circle arc freeform patch curve feature (plural allowed).
/// COND: atoms combined with and / or / not and parentheses. Atoms:
///   radius|area|length|half_angle|count OP EXPR   (OP: < <= > >= ==)
///   radius|area|length|half_angle ~ EXPR [+- EXPR]
///   normal|axis ~ DIR [+- DEG]  (DIR: ±x ±y ±z or a vector; 5° by default)
///   axis || DIR                 (parallel either way)
///   center ~ VEC +- EXPR
///   adjacent to NAME
/// PICKER: highest | lowest [along VEC] | largest | smallest | nearest VEC.
/// EXPR: numbers, parameters, NAME.PROP, [x, y, z], + - * / (also × ÷), parentheses, unary minus,
///       optional unit suffix mm | deg | rad.
#include <memory>
#include <string>
#include <vector>

#include "s2c/core/errors.h"

namespace s2c::edit {

/// A 1-based position in the script.
struct Location {
  int line = 0, column = 0;
};

/// A syntax or semantic error in a script. The message reads "FILE:LINE:COLUMN: WHAT".
struct ScriptError : InvalidInput {
  ScriptError(const std::string& source, Location at, const std::string& what);
  Location at;
};

struct Expr;
using ExprPtr = std::shared_ptr<const Expr>;

/// An arithmetic expression; its value is a number or a 3-vector.
struct Expr {
  enum class Kind { number, vector, name, property, negate, binary };
  Kind kind = Kind::number;
  Location at;
  double number = 0.0;        ///< number
  std::string name;           ///< name, property (the selection or parameter)
  std::string property;       ///< property: radius, half_angle, area, length, count, center, normal, axis
  char op = 0;                ///< binary: + - * /
  std::vector<ExprPtr> args;  ///< vector: 3, negate: 1, binary: 2
};

struct Condition;
using ConditionPtr = std::shared_ptr<const Condition>;

/// A condition on one feature (select … where, assert).
struct Condition {
  enum class Kind { compare, approx, direction, parallel_axis, near_point, adjacent, all_of, any_of, negate };
  Kind kind = Kind::compare;
  Location at;
  std::string property;  ///< compare/approx: radius area length half_angle count; direction: normal axis
  std::string op;        ///< compare: < <= > >= ==
  ExprPtr value;         ///< the number, direction or point compared with
  ExprPtr tolerance;     ///< approx / direction / near_point: the ± tolerance (may be null: defaults)
  std::string name;      ///< adjacent: the selection named
  std::vector<ConditionPtr> children;  ///< all_of / any_of / negate
};

enum class Picker { none, highest, lowest, largest, smallest, nearest };

/// `select TYPE [where COND] [PICKER]`.
struct Selector {
  std::string type;       ///< singular type word (plane … feature)
  ConditionPtr where;     ///< may be null
  Picker picker = Picker::none;
  ExprPtr picker_arg;     ///< nearest: the point; highest/lowest: the direction (null: +z)
};

struct Statement {
  enum class Kind { param, let_select, let_value, set, move, move_vertex, rotate, scale, constrain, unconstrain, lock, check, export_mesh };
  Kind kind = Kind::param;
  Location at;
  std::string text;                  ///< the statement's source line, trimmed (for messages)
  std::string name;                  ///< param / let / target name (set, move, rotate, scale, lock, assert)
  Location name_at;                  ///< where `name` was written
  std::string property;              ///< set: radius | half_angle; assert: the property tested
  ExprPtr value;                     ///< param/let/set value; move vector; rotate angle; scale factor; constrain value
  ExprPtr axis;                      ///< rotate: axis direction; move vertex: the vertex index
  ExprPtr pivot;                     ///< rotate/scale: `at` point (null: the feature's centre)
  Selector selector;                 ///< let_select
  std::string constraint;            ///< constrain / unconstrain / assert KIND(...): the kind name
  std::vector<std::string> members;  ///< constrain / unconstrain / assert KIND(...)
  std::vector<Location> member_at;   ///< where each member was written
  ConditionPtr condition;            ///< assert NAME.PROP …: the condition (applied to every feature)
  std::string path;                  ///< export
};

struct Script {
  std::string source;  ///< file name for messages
  std::vector<Statement> statements;
};

/// Parses a script. \throw ScriptError naming line, column, what was expected and what was found.
Script parse_script(const std::string& text, const std::string& source);

/// Parses one expression (a --set value). \throw ScriptError naming `source` and the column.
ExprPtr parse_expression(const std::string& text, const std::string& source);

/// The constraint kind names the language accepts (those of features.json).
const std::vector<std::string>& constraint_names();

}  // namespace s2c::edit
