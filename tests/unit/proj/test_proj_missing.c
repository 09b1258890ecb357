/* The coordinate systems' PROJ loader (src/crs/proj_api.c) when the library cannot be loaded:
 * compiled here against a soname that does not exist (tests/CMakeLists.txt), it must fail with
 * KARST_ENOTIMPL and a message naming PROJ, the soname and the Debian package, and give the
 * same answer on a second call (the load is tried once per process). That the real soname
 * loads and works is test_crs_frame's EPSG and datum-shift conversions, checked against cs2cs. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "crs/proj_api_internal.h"

static void test_missing_library(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  for (int round = 0; round < 2; round++) {
    assert_int_equal(karst_i_proj_load(&ctx), KARST_ENOTIMPL);
    assert_non_null(strstr(ctx.errmsg, "need PROJ"));
    assert_non_null(strstr(ctx.errmsg, KARST_PROJ_SONAME));
    assert_non_null(strstr(ctx.errmsg, "apt-get install libproj25"));
  }
  assert_null(karst_i_proj.proj_create);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_missing_library)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
