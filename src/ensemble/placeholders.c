/*
 * TEMPORARY weak stand-in for karst_file_hash (declared in scenario.h), whose
 * definition lands with the scenario branch. A weak symbol is replaced by the
 * real (strong) definition as soon as that exists, so this file changes
 * nothing once it is merged; delete it then.
 */
#include "karst/scenario.h"

__attribute__((weak)) karst_error_t karst_file_hash(karst_ctx_t *ctx, const char *path,
                                                    char out[17]) {
  (void)out;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: file hashing is not available yet", path);
}
