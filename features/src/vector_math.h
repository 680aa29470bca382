#pragma once
// Elementwise math over arrays, vectorised by glibc's libmvec (vector_math.cpp is the one file
// built with -ffast-math, which GCC needs before it calls libmvec's SIMD variants).
#include <cstddef>

namespace s2c::features {

/// x[i] = exp(x[i]) for i < n. libmvec's exp is within 4 ulp of the correctly rounded value
/// (std::exp: within 1); the tensor vote uses it for its decay weights.
void exp_in_place(double* x, std::size_t n);

/// x[i] = acos(x[i]) for i < n, each x[i] in [−1, 1] (libmvec: within 4 ulp). The fits' normal
/// angles, one per sample.
void acos_in_place(double* x, std::size_t n);

}  // namespace s2c::features
