/**
 * @file fuzz_util.h
 * @brief What the fuzz targets of tests/fuzz/ share: a quiet context and a per-process scratch
 *        file for the parsers that read a path (docs/fuzzing.md).
 */
#ifndef KARST_FUZZ_UTIL_H
#define KARST_FUZZ_UTIL_H

#include <stddef.h>
#include <stdint.h>

#include "karst/common.h"

/* libFuzzer's entry points, defined by each fuzz_<name>.c (LLVMFuzzerInitialize optional). */
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/** A context that prints nothing (no log function; errors stay in ctx->errmsg). */
void karst_fuzz_ctx(karst_ctx_t *ctx);

/**
 * Return @p err unchanged; when the environment variable KARST_FUZZ_VERBOSE is set (replay_<name>
 * run by hand on a seed), first print to stderr whether the parser accepted the input, or its
 * error message, so that a seed that no longer parses is seen.
 */
karst_error_t karst_fuzz_report(const karst_ctx_t *ctx, karst_error_t err);

/**
 * Write @p size bytes to the scratch file "<dir>/<name>" and return its path, where <dir> is
 * one mkdtemp directory per process (removed at exit) and @p name a fixed name whose extension
 * selects the reader. The same path is reused by every input; aborts when it cannot be written.
 */
const char *karst_fuzz_file(const char *name, const uint8_t *data, size_t size);

/** The scratch directory itself (created on first use), for targets that write several files. */
const char *karst_fuzz_dir(void);

/** A NUL-terminated copy of @p data (free() it), for parsers that take a C string. */
char *karst_fuzz_cstr(const uint8_t *data, size_t size);

#endif
