#include "vector_math.h"

#include <cmath>

namespace s2c::features {

void exp_in_place(double* x, std::size_t n) {
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) x[i] = std::exp(x[i]);
}

void acos_in_place(double* x, std::size_t n) {
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) x[i] = std::acos(x[i]);
}

}  // namespace s2c::features
