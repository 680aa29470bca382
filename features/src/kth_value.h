#pragma once
// The k-th smallest of many values on all cores (the noise's quartile and the median edge of a
// mesh: a few million values each, where std::nth_element on one core took 25 ms apiece).
#include <cstddef>
#include <vector>

namespace s2c::features {

/// The value std::nth_element would place at position k (k < values.size()); `values` may be
/// reordered. A sorted sample brackets the k-th value, the values inside the bracket are gathered
/// on all cores and the k-th is found among them; when the bracket misses it (values the sample
/// does not represent), nth_element over all of them.
double kth_value(std::vector<double>& values, std::size_t k);

}  // namespace s2c::features
