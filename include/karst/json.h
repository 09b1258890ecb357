/**
 * @file json.h
 * @brief A small JSON reader (RFC 8259) for the files karst writes and reads
 *        back: run.json and ensemble.json. It builds a tree of values;
 *        malformed input is an error naming FILE:LINE:COL. The writer side is
 *        karst_json_string in io.h.
 */
#ifndef KARST_JSON_H
#define KARST_JSON_H

#include <stddef.h>

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Deepest nesting of arrays and objects accepted (a guard for the recursive parser). */
#define KARST_JSON_MAX_DEPTH 256

typedef enum {
  KARST_JSON_NULL,
  KARST_JSON_FALSE,
  KARST_JSON_TRUE,
  KARST_JSON_NUMBER,
  KARST_JSON_STRING,
  KARST_JSON_ARRAY,
  KARST_JSON_OBJECT
} karst_json_type_t;

/** One JSON value. */
typedef struct karst_json {
  karst_json_type_t type;
  double number; /**< NUMBER: its value (strtod, correctly rounded) */
  char *text;    /**< STRING: the decoded UTF-8 text; NUMBER: the literal as written, so a
                      report shows it exactly; NULL for other types */
  karst_int_t n; /**< ARRAY, OBJECT: number of elements or members */
  struct karst_json *items; /**< ARRAY, OBJECT: the n values, in file order */
  char **keys;              /**< OBJECT: the n member names (decoded), in file order */
  int line, col;            /**< where the value starts (1-based; col counts bytes) */
} karst_json_t;

/**
 * Parse @p len bytes of @p text as one JSON value (an optional UTF-8 byte order
 * mark and surrounding white space allowed). @p source names the input in
 * messages ("FILE:LINE:COL: ..."). On success *@p out is a new tree (free with
 * karst_json_free); on failure *@p out is NULL and the error is KARST_EPARSE
 * (or KARST_ENOMEM). Duplicate member names in one object are an error.
 */
karst_error_t karst_json_parse(karst_ctx_t *ctx, const char *source, const char *text, size_t len,
                               karst_json_t **out);

/** Read and parse the file @p path (karst_json_parse with @p path as source). */
karst_error_t karst_json_read_file(karst_ctx_t *ctx, const char *path, karst_json_t **out);

/** Free a tree from karst_json_parse (NULL is allowed). */
void karst_json_free(karst_json_t *v);

/** The member @p key of the object @p obj, or NULL (also when @p obj is not an object). */
const karst_json_t *karst_json_get(const karst_json_t *obj, const char *key);

/** Non-zero for null, false, true, numbers and strings. */
int karst_json_is_scalar(const karst_json_t *v);

#ifdef __cplusplus
}
#endif
#endif
