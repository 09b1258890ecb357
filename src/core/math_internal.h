/* Inline replacements for libm's fmin and fmax (internal). GCC cannot inline fmin/fmax without
 * -ffinite-math-only, so each is a call into libm: in a run of the branchwork scenario about
 * 2.4 million of them (plane surface ranges, horizon terms of the edge costs, sampling and kNN
 * bounds), 1.5 % of its instructions with the calls' overhead (callgrind).
 *
 * These return exactly what glibc's x86-64 fmin/fmax return, bit for bit: a NaN argument yields
 * the other argument (C11 F.10.9.2-3) and, of two equal values, including -0 and +0, the first
 * is returned. Two NaNs give a NaN (its sign may differ from glibc's); a signalling NaN, which
 * no arithmetic produces, is returned as it is where glibc quiets it. tests/unit/test_core.c
 * compares them with fmin/fmax on signed zeros, infinities, NaNs, subnormals and random doubles.
 */
#ifndef KARST_CORE_MATH_INTERNAL_H
#define KARST_CORE_MATH_INTERNAL_H

static inline double karst_i_fmin(double a, double b) {
  return (a <= b || b != b) ? a : b;
}

static inline double karst_i_fmax(double a, double b) {
  return (a >= b || b != b) ? a : b;
}

#endif
