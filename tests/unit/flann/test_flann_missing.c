/* The FLANN loader (src/graph/flann_api.c) when the library cannot be loaded: compiled here
 * against a soname that does not exist (tests/CMakeLists.txt), it must fail with KARST_ENOTIMPL
 * and a message naming FLANN, the option that needs it, the soname and the Debian package, give
 * the same answer on a second call (the load is tried once per process), and leave no function
 * half-loaded. That the real soname loads and works is test_knn's FLANN search, which must
 * return the grid search's neighbour sets, and test_blocks' FLANN radius graph. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "graph/flann_api_internal.h"

static void test_missing_library(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  for (int round = 0; round < 2; round++) {
    assert_int_equal(karst_i_flann_load(&ctx), KARST_ENOTIMPL);
    assert_non_null(strstr(ctx.errmsg, "needs FLANN"));
    assert_non_null(strstr(ctx.errmsg, "sampling.knn: flann"));
    assert_non_null(strstr(ctx.errmsg, KARST_FLANN_SONAME));
    assert_non_null(strstr(ctx.errmsg, "apt-get install libflann1.9"));
  }
  assert_null(karst_i_flann.flann_build_index_double);
  assert_null(karst_i_flann.defaults);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_missing_library)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
