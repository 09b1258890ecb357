/* Number formatting for the text writers (internal). */
#ifndef KARST_IO_FORMAT_INTERNAL_H
#define KARST_IO_FORMAT_INTERNAL_H

#include <stddef.h>

/* Room for any karst_i_format_g17 result and its terminating NUL ("-1.2345678901234567e-308"). */
#define KARST_I_G17_SIZE 32

/**
 * Write @p v to @p out exactly as snprintf(out, KARST_I_G17_SIZE, "%.17g", v) does (17 significant
 * digits, correctly rounded, ties to even, trailing zeros dropped), without printf's arbitrary-
 * precision path: 128-bit integer arithmetic for 1e-6 <= |v| < 2^127, snprintf itself elsewhere
 * (zero, tiny, huge, infinite and NaN values). A Karstnet node file of 2 662 nodes took 34 M
 * instructions in fprintf, 2.3 % of a branchwork run (callgrind); tests/unit/test_read_karstnet.c
 * compares the two on several million values.
 * @return the length written (without the NUL).
 */
size_t karst_i_format_g17(double v, char out[KARST_I_G17_SIZE]);

#endif
