/* Error list, context, logging and progress (see include/karst/common.h). */
#include "karst/common.h"

#include <stdio.h>
#include <string.h>

static const char *const messages[] = {
#define KARST_X_MSG(code, msg) msg,
    KARST_ERROR_LIST(KARST_X_MSG)
#undef KARST_X_MSG
};

static const char *const names[] = {
#define KARST_X_NAME(code, msg) #code,
    KARST_ERROR_LIST(KARST_X_NAME)
#undef KARST_X_NAME
};

const char *karst_strerror(karst_error_t code) {
  if ((int)code < 0 || code >= KARST_ERROR_COUNT) return "unknown error";
  return messages[code];
}

const char *karst_error_name(karst_error_t code) {
  if ((int)code < 0 || code >= KARST_ERROR_COUNT) return "KARST_EUNKNOWN";
  return names[code];
}

void karst_ctx_init(karst_ctx_t *ctx) {
  memset(ctx, 0, sizeof *ctx);
  ctx->verbosity = KARST_LOG_WARNING;
  ctx->nthreads = 1;
}

karst_error_t karst_set_error(karst_ctx_t *ctx, karst_error_t code, const char *fmt, ...) {
  if (ctx == NULL) return code;
  ctx->errcode = code;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(ctx->errmsg, sizeof ctx->errmsg, fmt, ap);
  va_end(ap);
  return code;
}

void karst_log(const karst_ctx_t *ctx, karst_log_level_t level, const char *fmt, ...) {
  if (ctx == NULL || ctx->log == NULL || level > ctx->verbosity) return;
  char buf[2048];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  ctx->log(ctx->log_user, level, buf);
}

void karst_progress(const karst_ctx_t *ctx, const char *stage, double done, double total) {
  if (ctx == NULL || ctx->progress == NULL) return;
  ctx->progress(ctx->progress_user, stage, done, total);
}

int karst_interrupted(const karst_ctx_t *ctx) {
  return ctx != NULL && ctx->interrupt != NULL && *ctx->interrupt != 0;
}
