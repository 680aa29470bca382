#pragma once
// The k-th smallest of many values on all cores (the noise's quartile and the median edge of a
// mesh: a few million values each, where std::nth_element on one core took 25 ms apiece).
#include <cstddef>
#include <vector>

namespace s2c::features {

/// The value std::nth_element would place at position k (k < values.size()); `values` may be
/// reordered. A sorted sample brackets the k-th value and the values are counted against it on all
/// cores; then the k-th is the bracket's one value when it holds one (a CAD mesh's flat edges),
/// else it is found among the values inside, gathered on all cores. When the bracket misses it
/// (values the sample does not represent), holds a quarter of them or more, or a value is NaN,
/// nth_element over all of them.
double kth_value(std::vector<double>& values, std::size_t k);

}  // namespace s2c::features
