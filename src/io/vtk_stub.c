/* Placeholder until the VTK shim (src/io/vtk_shim.cpp) exists. */
#include "karst/vtk.h"

karst_error_t karst_vtk_write_network(karst_ctx_t *ctx, const char *path, const karst_network_t *net) {
  (void)net;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: VTK output is not available yet", path);
}
karst_error_t karst_vtk_read_network(karst_ctx_t *ctx, const char *path, karst_network_t *net) {
  (void)net;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: VTK input is not available yet", path);
}
karst_error_t karst_vtk_write_samples(karst_ctx_t *ctx, const char *path, const karst_samples_t *s) {
  (void)s;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: VTK output is not available yet", path);
}
karst_error_t karst_vtk_write_mesh(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m) {
  (void)m;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: VTK output is not available yet", path);
}
karst_error_t karst_vtk_write_image(karst_ctx_t *ctx, const char *path, const int dims[3],
                                    const double origin[3], const double spacing[3],
                                    const float *values, const char *name) {
  (void)dims, (void)origin, (void)spacing, (void)values, (void)name;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: VTK output is not available yet", path);
}
karst_error_t karst_vtk_write_pvd(karst_ctx_t *ctx, const char *path, int n, const char *const *files) {
  (void)n, (void)files;
  return karst_set_error(ctx, KARST_ENOTIMPL, "%s: VTK output is not available yet", path);
}
