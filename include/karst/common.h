/**
 * @file common.h
 * @brief Core conventions shared by every karst module: the index type, the
 *        error list, the explicit context (logging, progress, error message)
 *        and the seeded random generator with independent streams.
 */
#ifndef KARST_COMMON_H
#define KARST_COMMON_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** One index type for vertices, edges and counts (igraph's igraph_integer_t). */
typedef int64_t karst_int_t;

/* ------------------------------------------------------------------------ */
/* Errors: one X-macro list so that codes and messages cannot drift apart.   */
/* ------------------------------------------------------------------------ */
#define KARST_ERROR_LIST(X)                                                     \
  X(KARST_SUCCESS, "success")                                                  \
  X(KARST_ENOMEM, "out of memory")                                             \
  X(KARST_EINVAL, "invalid value")                                             \
  X(KARST_EIO, "input/output error")                                           \
  X(KARST_EPARSE, "malformed input")                                           \
  X(KARST_ERANGE, "value out of range")                                        \
  X(KARST_ENOTFOUND, "not found")                                              \
  X(KARST_EUNSUPPORTED, "not supported")                                       \
  X(KARST_EUNREACHABLE, "a key point cannot be connected")                     \
  X(KARST_EINTERRUPTED, "interrupted")                                         \
  X(KARST_EEXTERNAL, "an external program or library failed")                 \
  X(KARST_EBUSY, "in use by another process")                                 \
  X(KARST_ENOTIMPL, "not available yet")

typedef enum {
#define KARST_X_ENUM(code, msg) code,
  KARST_ERROR_LIST(KARST_X_ENUM)
#undef KARST_X_ENUM
      KARST_ERROR_COUNT
} karst_error_t;

/** Short message for an error code (never NULL). */
const char *karst_strerror(karst_error_t code);
/** Name of an error code, e.g. "KARST_EPARSE" (never NULL). */
const char *karst_error_name(karst_error_t code);

/* ------------------------------------------------------------------------ */
/* Context: what a computation needs travels explicitly (qhull's qhT).       */
/* ------------------------------------------------------------------------ */
typedef enum {
  KARST_LOG_ERROR = 0,
  KARST_LOG_WARNING = 1,
  KARST_LOG_INFO = 2,
  KARST_LOG_DEBUG = 3
} karst_log_level_t;

typedef void (*karst_log_fn)(void *user, karst_log_level_t level, const char *message);
/** Progress of a long stage: @p done out of @p total units of work. */
typedef void (*karst_progress_fn)(void *user, const char *stage, double done, double total);

#define KARST_ERRMSG_MAX 2048

typedef struct karst_ctx {
  karst_log_fn log;              /**< NULL: messages are dropped. */
  void *log_user;
  karst_log_level_t verbosity;   /**< messages above this level are dropped. */
  karst_progress_fn progress;    /**< NULL: no progress reports. */
  void *progress_user;
  int nthreads;                  /**< worker threads a stage may use (>= 1). */
  volatile int *interrupt;       /**< when non-NULL and non-zero, long loops stop with KARST_EINTERRUPTED. */
  karst_error_t errcode;         /**< last error set with karst_set_error(). */
  char errmsg[KARST_ERRMSG_MAX]; /**< its message: what was wrong, with which value. */
} karst_ctx_t;

/** Initialise a context: no logging, no progress, one thread, empty error. */
void karst_ctx_init(karst_ctx_t *ctx);

/**
 * Record an error in @p ctx and return @p code, so that callers write
 * `return karst_set_error(ctx, KARST_ERANGE, "%s:%d:%d: dip must be ...", ...)`.
 * The message says what was wrong and with which value. A NULL @p ctx is allowed.
 */
karst_error_t karst_set_error(karst_ctx_t *ctx, karst_error_t code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/** Send a message to the context's logger when the level is enabled. */
void karst_log(const karst_ctx_t *ctx, karst_log_level_t level, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/** Report progress (no-op without a callback). */
void karst_progress(const karst_ctx_t *ctx, const char *stage, double done, double total);

/** Non-zero when the user asked to stop (ctx->interrupt set). */
int karst_interrupted(const karst_ctx_t *ctx);

/* ------------------------------------------------------------------------ */
/* Random numbers: xoshiro256** seeded through SplitMix64.                  */
/* Streams are derived from (seed, stream) so a realisation does not depend */
/* on thread or process count.                                              */
/* ------------------------------------------------------------------------ */
typedef struct karst_rng {
  uint64_t s[4];
} karst_rng_t;

/**
 * Seed @p rng with the stream identified by (@p seed, @p stream). Different
 * streams are statistically independent (SplitMix64 mixing of both words).
 * Time complexity: O(1).
 */
void karst_rng_init(karst_rng_t *rng, uint64_t seed, uint64_t stream);
/** Derive a child stream (e.g. one per pipeline stage) from a parent's seed words. */
void karst_rng_derive(karst_rng_t *child, uint64_t seed, uint64_t stream, uint64_t substream);
/** Next 64 random bits. */
uint64_t karst_rng_u64(karst_rng_t *rng);
/** Uniform double in [0, 1) with 53 random bits. */
double karst_rng_uniform(karst_rng_t *rng);
/** Uniform double in [a, b). */
double karst_rng_uniform_range(karst_rng_t *rng, double a, double b);
/** Uniform integer in [0, n) without modulo bias; n must be > 0. */
uint64_t karst_rng_below(karst_rng_t *rng, uint64_t n);
/** Standard normal variate (Marsaglia polar method). */
double karst_rng_gaussian(karst_rng_t *rng);
/** Uniform direction on the unit sphere. */
void karst_rng_unit_vector(karst_rng_t *rng, double v[3]);

/** Library version string, e.g. "0.1.0". */
const char *karst_version(void);

#ifdef __cplusplus
}
#endif
#endif /* KARST_COMMON_H */
