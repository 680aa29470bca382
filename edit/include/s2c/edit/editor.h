#pragma once
/// \file Feature-based editing of a mesh with its hyper-mesh (paper §4, "bubbling and propagation").
///
/// An Editor holds a mesh and its features (features.json). Every edit is a transaction: it either
/// applies completely or throws and leaves mesh and features as they were.
///
/// What one edit does:
///  1. The edited features get their new shape (a cylinder's radius, a plane moved or rotated, …)
///     and their vertices are placed exactly on it: the feature's shape map moves every vertex.
///  2. Greedy constraint propagation (paper §4.3): for every constraint group holding an edited
///     feature, members that no longer satisfy it are adjusted with the smallest change of their
///     shape that does (rotate to parallel, move onto the axis, take the radius, …) and propagate
///     in turn, until already modified features. A constraint that would have to change a locked
///     or already modified feature, or that has no adjustment, is a conflict: ProcessingError.
///  3. The neighbourhood follows with As-Rigid-As-Possible deformation (Sorkine & Alexa 2007,
///     cotangent weights), restricted as in paper §4.2: patches that share a vertex with the
///     modified features are free, every other vertex stays where it is (displacement exactly 0).
///     The sparse factorisation is cached and reused while the same region is edited again.
///  4. Free analytic patches go back onto the shape their border spans, each vertex keeping its
///     offset from it: a CAD tessellation lands exactly on it, so planes stay planes.
///  5. The region is checked: a flipped or degenerate triangle is a ProcessingError.
/// Low-level edits (move_vertices) "bubble up": only the features the vertices belong to change.
///
/// Example (C++):
/// \code
///   s2c::edit::Editor ed(s2c::read_mesh("part.ply"), s2c::features::read_features("features.json"));
///   auto holes = ed.select([&](s2c::edit::FeatureRef f) { return ed.shape(f).type == ShapeType::cylinder; });
///   ed.set_radius(holes, 4.0);                    // equal_radius partners follow
///   ed.move({*ed.find("P3")}, {0, 0, 2});
///   s2c::write_mesh(ed.mesh(), "edited.ply");
/// \endcode
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "s2c/core/mesh.h"
#include "s2c/features/feature_set.h"

namespace s2c::edit {

/// A patch or a line of the feature set, by index.
struct FeatureRef {
  enum class Kind { patch, line };
  Kind kind = Kind::patch;
  int index = 0;
  bool operator==(const FeatureRef& o) const { return kind == o.kind && index == o.index; }
  bool operator!=(const FeatureRef& o) const { return !(*this == o); }
  bool operator<(const FeatureRef& o) const { return kind != o.kind ? kind < o.kind : index < o.index; }
};

struct EditOptions {
  int arap_iterations = 20;              ///< ARAP local/global iterations at most
  double arap_tolerance = 1e-6;          ///< stop when the relative energy change is below this
  double angle_tolerance_deg = 0.01;     ///< a constraint holds when its angle residual is below this
  double length_tolerance = 1e-3;        ///< … and its length / position residual below this, mm
  bool propagate = true;                 ///< greedy constraint propagation
  /// Put a free analytic patch whose fit rms is at most this (mm) back onto the shape its border
  /// spans, each vertex keeping its offset from the surface: a CAD tessellation lands exactly on
  /// it (planes stay planes); on a scan only vertices whose faces lie along the surface move, and
  /// a snap that would fold a triangle is undone. < 0: never (ARAP's result stays).
  double snap_max_rms = 0.1;
  /// For comparison only (benchmarks): ARAP over every patch of the mesh instead of the 1-ring of
  /// the modified features (the handles are then the only constraints).
  bool whole_mesh = false;
  /// Patches smaller than this fraction of the total area (and freeform ones) are crumbs: they pass
  /// the freedom of the 1-ring on to their neighbours.
  double small_patch_fraction = 0.002;
  /// A crumb touching a modified patch (directly or through other crumbs) whose every vertex lies
  /// within this fraction of the mesh's bounding-box diagonal of the patch's surface belongs to
  /// it: it takes the patch's map (a scan's hole wall left in pieces, a rounded rim). ≤ 0: never.
  double carry_band_fraction = 0.01;
  /// Free vertices lie within influence × half the size of the largest modified feature (at least
  /// 4× the largest displacement) of a moved vertex; the rest of a free patch stays fixed, so an
  /// edit of a hole costs the same in a plane of 1k or of 1M vertices. ≤ 0: whole free patches.
  double influence = 0.5;
  /// When triangles fold, free up to this many further rings of patches (and double the reach)
  /// before giving up.
  int max_extra_rings = 2;
};

/// What one edit did.
struct EditReport {
  std::vector<FeatureRef> edited;       ///< the features the call named
  std::vector<FeatureRef> propagated;   ///< features changed by constraint propagation, in order
  std::vector<std::string> propagation; ///< one line per propagation step ("parallel G3: P2 rotated 15°")
  std::vector<FeatureRef> carried;      ///< crumbs moved with the modified patch they belong to
  std::vector<FeatureRef> free;         ///< patches deformed by ARAP
  int handle_vertices = 0;              ///< vertices placed by shape maps
  int free_vertices = 0;                ///< vertices solved by ARAP
  int arap_iterations = 0;
  bool factorization_reused = false;
  int extra_rings = 0;                  ///< rings freed beyond the first because triangles folded
  double max_displacement = 0.0;        ///< mm
  double seconds = 0.0;
  /// Where the seconds went: shape maps and propagation, finding the region, building the ARAP
  /// factorisation, ARAP iterations, putting CAD patches back on their shapes, the fold check,
  /// updating the features.
  struct Times {
    double propagation = 0, region = 0, factorization = 0, solve = 0, snap = 0, check = 0, commit = 0;
  } time;
  /// Constraints among features the edit did not set (ARAP neighbours, lines) that no longer hold:
  /// reported here and removed from features(), never kept as a false statement.
  std::vector<std::string> broken;
};

/// Residual of one constraint group on the current shapes.
struct ConstraintResidual {
  double angle_deg = 0.0;  ///< angular part
  double length = 0.0;     ///< length / position part, mm
  bool checked = false;    ///< false when the kind or the members' shapes have no measurable residual
};

class Editor {
 public:
  /// \throw InvalidInput when the features do not belong to the mesh (counts, indices out of range).
  Editor(Mesh mesh, features::FeatureSet features, EditOptions options = {});
  ~Editor();
  Editor(Editor&&) noexcept;
  Editor& operator=(Editor&&) noexcept;

  const Mesh& mesh() const;
  /// The features with shapes of edited, propagated and deformed features updated (refitted where
  /// ARAP moved them; exact where an edit set them) and the constraint groups as edited.
  const features::FeatureSet& features() const;
  const EditOptions& options() const;

  // ---- features -------------------------------------------------------------------------------
  std::vector<FeatureRef> all() const;
  std::optional<FeatureRef> find(const std::string& id) const;
  const std::string& id(FeatureRef f) const;
  const features::Shape& shape(FeatureRef f) const;
  /// Area-weighted centroid (patches) or mean vertex (lines), mm.
  Eigen::Vector3d centroid(FeatureRef f) const;
  double area(FeatureRef f) const;    ///< patches: mm²; lines: 0
  double length(FeatureRef f) const;  ///< lines: polyline length, mm; patches: 0
  /// Features sharing a mesh vertex with f (paper: "even one shared vertex makes a neighbour").
  std::vector<FeatureRef> neighbours(FeatureRef f) const;
  std::vector<FeatureRef> select(const std::function<bool(FeatureRef)>& keep) const;
  /// Mesh vertices of a feature (patches: of their faces), sorted.
  const std::vector<int>& vertices(FeatureRef f) const;

  // ---- edits (transactions) ---------------------------------------------------------------------
  /// Cylinders, spheres, circles, arcs: the radius, mm (> 0). \throw InvalidInput for other shapes.
  EditReport set_radius(const std::vector<FeatureRef>& f, double radius);
  /// Cones: the half angle, degrees, in (0, 90). \throw InvalidInput for other shapes.
  EditReport set_half_angle(const std::vector<FeatureRef>& f, double degrees);
  EditReport move(const std::vector<FeatureRef>& f, const Eigen::Vector3d& by);
  /// Rotates about the line through `pivot` (default: the selection's centroid) along `axis`.
  EditReport rotate(const std::vector<FeatureRef>& f, const Eigen::Vector3d& axis, double degrees,
                    const std::optional<Eigen::Vector3d>& pivot = std::nullopt);
  /// Uniform scale about `pivot` (default: the selection's centroid); factor > 0.
  EditReport scale(const std::vector<FeatureRef>& f, double factor,
                   const std::optional<Eigen::Vector3d>& pivot = std::nullopt);
  /// Low-level edit: moves the given vertices to the targets; the features they belong to follow.
  EditReport move_vertices(const std::vector<int>& vertices, const std::vector<Eigen::Vector3d>& targets);

  // ---- constraints ------------------------------------------------------------------------------
  /// Locked features never move: an edit that would move one (other than by ARAP's neighbours rule,
  /// which keeps them fixed anyway) is a conflict.
  void lock(FeatureRef f);
  bool locked(FeatureRef f) const;
  /// Adds a constraint group and enforces it by adjusting the members after the first (which
  /// propagates). Returns the edit report. \throw InvalidInput when the kind does not apply to the
  /// members' shapes; ProcessingError when it cannot be met.
  EditReport constrain(features::ConstraintKind kind, const std::vector<FeatureRef>& members,
                       std::optional<double> value = std::nullopt);
  /// Removes constraint groups of `kind` whose members include all of `members` (when kind is
  /// empty: every constraint group containing any of them). Returns how many groups it removed.
  int unconstrain(std::optional<features::ConstraintKind> kind, const std::vector<FeatureRef>& members);
  /// Residual of a constraint group (by index into features().groups).
  ConstraintResidual residual(int group) const;
  /// The constraint groups (indices) that hold any of the features.
  std::vector<int> constraints_of(const std::vector<FeatureRef>& f) const;

  /// Displacement of every vertex from the mesh the editor was built with, mm.
  std::vector<double> displacement() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace s2c::edit
