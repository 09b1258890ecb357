/* The VTK plugin's loader (src/io/vtk_api.c) when the plugin cannot be loaded: compiled here
 * against a plugin name that does not exist (tests/CMakeLists.txt), every call that needs VTK
 * must fail with KARST_EEXTERNAL and a message naming the file, VTK and the plugin, give the same
 * answer on a second call (the load is tried once per process), and the decompression of
 * vtp_check.c must report failure rather than crash. Writing .vtp files must not need the
 * plugin at all (libkarst's own karst_vtk_write_network, left unrenamed, still works). That the
 * real plugin loads and works is test_vtk's and test_vtp_write's business. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "io/vtk_api_internal.h"
#include "karst.h"

karst_error_t test_vtk_read_network(karst_ctx_t *ctx, const char *path, karst_network_t *net);
karst_error_t test_vtk_write_image(karst_ctx_t *ctx, const char *path, const int dims[3],
                                   const double origin[3], const double spacing[3],
                                   const float *values, const char *name);
int test_i_vtk_uncompress(int compressor, const unsigned char *in, size_t in_len,
                          unsigned char *out, size_t out_len);

static void test_missing_plugin(void **state) {
  (void)state;
  for (int round = 0; round < 2; round++) {
    karst_ctx_t ctx;
    karst_ctx_init(&ctx);
    karst_network_t net;
    karst_network_init(&net);
    assert_int_equal(test_vtk_read_network(&ctx, "cave.vtp", &net), KARST_EEXTERNAL);
    assert_non_null(strstr(ctx.errmsg, "cave.vtp"));
    assert_non_null(strstr(ctx.errmsg, "VTK"));
    assert_non_null(strstr(ctx.errmsg, "libkarst-test-no-such-vtk.so"));
    assert_int_equal(net.n_nodes, 0);
    const int dims[3] = {2, 2, 2};
    const double o[3] = {0, 0, 0}, h[3] = {1, 1, 1};
    const float v[8] = {0};
    assert_int_equal(test_vtk_write_image(&ctx, "/tmp/never.vti", dims, o, h, v, "sdf"),
                     KARST_EEXTERNAL);
    assert_non_null(strstr(ctx.errmsg, "/tmp/never.vti"));
    assert_int_equal(access("/tmp/never.vti", F_OK), -1);
    unsigned char in[4] = {0}, out[4];
    assert_int_equal(test_i_vtk_uncompress(1, in, 4, out, 4), -1);
  }
  /* the .vtp writers are libkarst's own: no VTK needed */
  karst_network_t net;
  karst_network_init(&net);
  assert_int_equal(karst_network_add_node(&net, 1, 2, 3, NULL), KARST_SUCCESS);
  char path[] = "/tmp/karst_test_vtk_missing_XXXXXX";
  int fd = mkstemp(path);
  assert_true(fd >= 0);
  close(fd);
  assert_int_equal(karst_vtk_write_network(NULL, path, &net), KARST_SUCCESS);
  remove(path);
  karst_network_destroy(&net);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_missing_plugin)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
