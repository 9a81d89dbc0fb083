#pragma once
// The natural logarithm in arithmetic the compiler can vectorise: libm's log is a call, which stops the
// vectoriser and, inside a hot loop, spills its live vector registers. Here every branch is a bit mask, so a loop
// over particles that takes a log runs 4 of them at once in the AVX2 copy of the kernels (kernels/isa.hpp); the
// SSE2 code would run it scalar (SSE2 has no 64-bit integer compares), at more instructions than libm's log, so
// kernels take their log by log_for, which picks one of the two by the instruction set they are compiled for.
//
// The method is fdlibm's (e_log.c): x = 2^k m with m in [√2/2, √2), f = m − 1, s = f/(2 + f), and
// log(1 + f) = f − f²/2 + s (f²/2 + R(s²)), R a degree-14 minimax polynomial in s with its published
// coefficients; k ln 2 is added in two parts so that the sum stays exact. It agrees with glibc's log to 1 ulp
// (tests/test_vector_log.cpp) and returns what log returns for 0 (−∞), +∞ (+∞), negatives and NaN (NaN).
#include <bit>
#include <cmath>
#include <cstdint>

#include "kernels/isa.hpp"

namespace mpm {

inline double vector_log(double x) {
  using u64 = std::uint64_t;
  constexpr u64 one = 0x3ff0000000000000, sqrt_half = 0x3fe6a09e667f3bcd, mantissa = 0x000fffffffffffff;
  constexpr u64 smallest_normal = 0x0010000000000000, infinity = 0x7ff0000000000000;
  const u64 bits = std::bit_cast<u64>(x);
  // subnormals are scaled by 2^52 into the normal range (a multiplication by 1 otherwise)
  const u64 subnormal = bits < smallest_normal;
  const double scaled = x * std::bit_cast<double>(one + (subnormal * 52 << 52));
  // offsetting the bits by one − bits(√2/2) carries the exponent over exactly when the mantissa passes √2/2
  const u64 shifted = std::bit_cast<u64>(scaled) + (one - sqrt_half);
  // k + 1023 of the scaled x, as a double (exact); a subnormal's k is 52 less, subtracted as a double (in the
  // integer the difference would wrap below zero)
  const double biased_k = std::bit_cast<double>((shifted >> 52) | 0x4330000000000000) - 0x1p52;
  const double k = biased_k - 1023 - std::bit_cast<double>(-subnormal & std::bit_cast<u64>(52.0));
  const double m = std::bit_cast<double>((shifted & mantissa) + sqrt_half);
  const double f = m - 1, s = f / (2 + f), z = s * s, w = z * z;
  const double odd = z * (6.666666666666735130e-01 +
                          w * (2.857142874366239149e-01 + w * (1.818357216161805012e-01 + w * 1.479819860511658591e-01)));
  const double even = w * (3.999999999940941908e-01 + w * (2.222219843214978396e-01 + w * 1.531383769920937332e-01));
  const double half_f2 = 0.5 * f * f;
  constexpr double ln2_hi = 6.93147180369123816490e-01, ln2_lo = 1.90821492927058770002e-10;
  const double log_x = k * ln2_hi - ((half_f2 - (s * (half_f2 + odd + even) + k * ln2_lo)) - f);
  // positive, finite, nonzero x: log_x; otherwise −∞ for ±0, +∞ for +∞, NaN for the rest
  const u64 finite_positive = -static_cast<u64>(bits - 1 < infinity - 1);
  const u64 zero = -static_cast<u64>(bits << 1 == 0), plus_infinity = -static_cast<u64>(bits == infinity);
  const u64 special = (zero & 0xfff0000000000000) | (plus_infinity & infinity) |
                      (~(zero | plus_infinity) & 0x7ff8000000000000);
  return std::bit_cast<double>((std::bit_cast<u64>(log_x) & finite_positive) | (special & ~finite_positive));
}

/// The log for code compiled for instruction set I: vector_log where it runs in vector lanes (AVX2), libm's log
/// where it would run scalar (SSE2) and cost more instructions than libm's (docs/PERFORMANCE.md).
template <Isa I>
inline double log_for(double x) {
  if constexpr (has_avx2<I>) return vector_log(x);
  else return std::log(x);
}

}  // namespace mpm
