#pragma once
// Small topology helpers on an indexed triangle soup, shared by cleaning, the defect report and
// the repair driver: undirected edge keys, edge → faces, components.
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <utility>
#include <vector>

#include "s2c/core/mesh.h"

namespace s2c::repair {

inline std::uint64_t undirected_key(int a, int b) { return undirected_edge_key(a, b); }

/// Faces of every undirected edge, in flat arrays: edge keys sorted, each edge's faces ascending
/// (a hash map of vectors allocated per edge and was a fifth of a volumetric repair's time).
/// Iterates as (key, faces) pairs; `at` finds one edge by binary search.
class EdgeFaces {
 public:
  struct Faces {
    const int *first, *last;
    const int* begin() const { return first; }
    const int* end() const { return last; }
    std::size_t size() const { return static_cast<std::size_t>(last - first); }
    int operator[](std::size_t i) const { return first[i]; }
  };
  class Iterator {
   public:
    Iterator(const EdgeFaces* owner, std::size_t i) : owner_(owner), i_(i) {}
    std::pair<std::uint64_t, Faces> operator*() const { return {owner_->keys_[i_], owner_->faces_of(i_)}; }
    Iterator& operator++() { ++i_; return *this; }
    bool operator!=(const Iterator& o) const { return i_ != o.i_; }
    bool operator==(const Iterator& o) const { return i_ == o.i_; }
    using iterator_category = std::input_iterator_tag;
    using value_type = std::pair<std::uint64_t, Faces>;
    using difference_type = std::ptrdiff_t;
    using pointer = void;
    using reference = value_type;

   private:
    const EdgeFaces* owner_;
    std::size_t i_;
  };
  explicit EdgeFaces(const TriangleSoup& soup);
  Iterator begin() const { return {this, 0}; }
  Iterator end() const { return {this, keys_.size()}; }
  std::size_t size() const { return keys_.size(); }
  /// \throw std::out_of_range when no face has the edge.
  Faces at(std::uint64_t key) const;

 private:
  Faces faces_of(std::size_t i) const { return {faces_.data() + start_[i], faces_.data() + start_[i + 1]}; }
  std::vector<std::uint64_t> keys_;
  std::vector<int> start_, faces_;
};

inline EdgeFaces edge_faces(const TriangleSoup& soup) { return EdgeFaces(soup); }

/// Vertex-connected components of the faces: component id per face, and the count.
std::vector<int> face_components(const TriangleSoup& soup, int& count);

double face_area(const TriangleSoup& soup, int face);

/// Per component (ids of face_components): open (has a boundary edge) and with less than
/// `fraction` of the total area. Such components are scanner fragments and loose triangles.
std::vector<char> tiny_open_components(const TriangleSoup& soup, const std::vector<int>& comp, int count,
                                       double fraction = 0.005);

/// Exactly collinear corners (or repeated indices).
bool zero_area(const TriangleSoup& soup, int face);

/// Drops vertices no face uses and renumbers; returns how many were dropped.
std::size_t remove_unreferenced(TriangleSoup& soup);

}  // namespace s2c::repair
