/**
 * @file input_internal.h
 * @brief The one guarded way karst opens an input file (not part of the
 *        public API): a regular file only (no directory, FIFO, device or
 *        socket, so nothing blocks or reads forever), at most a size cap
 *        named by the format, and reads bounded by what the file holds.
 *
 * Every reader of the library (surveys, .vtp, scenario, heightfield, TSurf,
 * images, tables, JSON) opens its file through karst_i_open_regular() or
 * karst_i_read_regular().
 */
#ifndef KARST_IO_INPUT_INTERNAL_H
#define KARST_IO_INPUT_INTERNAL_H

#include <stddef.h>
#include <stdio.h>

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Survey and network text/binary files (.3d, .sql, .pl, Karstnet .dat, .svx). */
#define KARST_SURVEY_MAX_BYTES (512LL << 20)
/** VTK XML PolyData (.vtp) read as a network. */
#define KARST_VTP_MAX_BYTES (2LL << 30)
/** CSV tables (--observed-table, --published, ensemble tables). */
#define KARST_TABLE_MAX_BYTES (256LL << 20)
/** JSON documents (ensemble.json, ...). */
#define KARST_JSON_MAX_BYTES (256LL << 20)
/** The largest cap of any reader (heightfield, TSurf, .vtp): for hashing an input file. */
#define KARST_INPUT_MAX_BYTES (2LL << 30)

/**
 * Open @p path for reading only when it is a regular file of at most
 * @p max_bytes bytes. The type is checked with stat() before opening, so a
 * FIFO is refused without blocking and /dev/zero without reading forever;
 * what was opened is checked again with fstat().
 * @p what names the file in messages ("scenario", "heightfield", "survey").
 * @return KARST_SUCCESS with *fp open, KARST_ENOTFOUND (missing), KARST_EIO
 *         (unreadable, not a regular file) or KARST_ERANGE (too large);
 *         ctx->errmsg starts with "PATH: ".
 * Time complexity: O(1).
 */
karst_error_t karst_i_open_regular(karst_ctx_t *ctx, const char *path, const char *what,
                                   long long max_bytes, FILE **fp);

/**
 * Read the whole of @p path (opened with karst_i_open_regular) into a
 * malloc'd, NUL-terminated buffer. The buffer is sized from the file's size
 * and the read stops there: a file that grows while being read past
 * @p max_bytes is refused (KARST_ERANGE) instead of being followed.
 * @param data receives the buffer (free() it); @param len its length without the NUL.
 * Time complexity: O(file size).
 */
karst_error_t karst_i_read_regular(karst_ctx_t *ctx, const char *path, const char *what,
                                   long long max_bytes, unsigned char **data, size_t *len);

/**
 * Check that @p path could be opened by karst_i_open_regular (exists, is a
 * regular file within @p max_bytes) without opening it; for inputs handed to
 * another program (cavern) or to a library that opens the file itself.
 */
karst_error_t karst_i_check_regular(karst_ctx_t *ctx, const char *path, const char *what,
                                    long long max_bytes);

/**
 * Validate a VTK XML PolyData file before VTK parses it (src/io/vtp_check.c):
 * XML nesting of VTKFile/PolyData/Piece/Points/cells/DataArray, piece counts
 * and NumberOfComponents within what the file could hold, binary block
 * headers (inline base64 or appended, raw or base64, compressed or not)
 * consistent with the bytes present, and finite ASCII point coordinates.
 * Opens the file with karst_i_read_regular (KARST_VTP_MAX_BYTES).
 * @return KARST_SUCCESS, or KARST_EPARSE / KARST_ERANGE / KARST_EUNSUPPORTED
 *         with "PATH: ELEMENT ...: message" (byte offset of the element).
 * Time complexity: O(file size).
 */
karst_error_t karst_i_vtp_check(karst_ctx_t *ctx, const char *path);

/** karst_i_vtp_check on bytes already in memory (@p name for messages). */
karst_error_t karst_i_vtp_check_buffer(karst_ctx_t *ctx, const char *name,
                                       const unsigned char *data, size_t len);

/**
 * A decimal number "[+-]digits[.digits][(e|E)[+-]digits]" (at least one mantissa digit) filling
 * s[0 .. len) exactly, by Clinger's fast path (W. D. Clinger, "How to read floating point
 * numbers accurately", PLDI 1990): when its significant digits make an integer m <= 2^53 and
 * its decimal exponent e is within [-22, 22], m and 10^|e| are exact doubles and one correctly
 * rounded product or quotient is the correctly rounded value, strtod's. On x86 the same with
 * m < 2^64 and |e| <= 27 in x87 extended precision (64-bit significand), which then rounds
 * twice: declined when the extended result lies exactly halfway between two doubles, the only
 * case where the second rounding can differ from strtod's, or is not a normal double. Returns
 * 1 with *out set; 0 for anything else (more than 19 significant digits, a larger exponent,
 * hexadecimal, inf, nan, other characters), which the caller hands to strtod.
 * Time complexity: O(len).
 */
int karst_i_parse_decimal(const char *s, size_t len, double *out);

#ifdef __cplusplus
}
#endif

#endif
