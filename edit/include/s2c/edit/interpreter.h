#pragma once
/// \file Running an edit script (s2c/edit/script.h) on an Editor.
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "s2c/edit/editor.h"
#include "s2c/edit/script.h"

namespace s2c::edit {

struct ScriptOptions {
  /// --set NAME=VALUE: overrides `param NAME = …` (VALUE is an expression: "4", "[0, 0, 2]", "2*3").
  std::map<std::string, std::string> overrides;
  /// Called with one or more lines per statement: what it selects and what it changes.
  std::function<void(const std::string&)> say;
};

/// What one statement did.
struct StatementReport {
  int line = 0;
  std::string text;
  std::vector<std::string> selected;  ///< feature ids the statement acted on or tested
  EditReport edit;                    ///< for edits
};

struct ScriptResult {
  std::vector<StatementReport> statements;
  /// `export "PATH"` statements: the path as written and the mesh at that point. Nothing is written
  /// by run_script: the caller writes them after the whole script has succeeded.
  std::vector<std::pair<std::filesystem::path, Mesh>> exports;
  int asserts = 0;  ///< asserts that passed
};

/// Runs every statement in order.
/// \throw ScriptError (exit 2) for a statement that cannot run as written: an unknown name, a type
///        error, an edit on an empty selection, a property the feature does not have, an unknown
///        --set name. The message names file, line and column.
/// \throw ProcessingError (exit 3) for a failed assert or an edit that cannot be satisfied
///        (a conflict, a folded triangle), naming file, line and the statement.
ScriptResult run_script(const Script& script, Editor& editor, const ScriptOptions& options = {});

}  // namespace s2c::edit
