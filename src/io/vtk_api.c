/* The VTK plugin loaded on first use (src/io/vtk_api_internal.h), and the functions of
 * include/karst/vtk.h and io/vtk_reference_internal.h that go through it. */
#include "io/vtk_api_internal.h"

#include <pthread.h>
#include <stdio.h>

#include "core/library_internal.h"
#include "io/vtk_reference_internal.h"
#include "io/vtp_write_internal.h"

#ifndef KARST_VTK_PLUGIN
#define KARST_VTK_PLUGIN 1
#endif

static pthread_once_t once = PTHREAD_ONCE_INIT;
static const karst_i_vtk_api_t *loaded;
static char load_error[1024]; /* why the load failed; empty when it succeeded */

static void load(void) {
#if KARST_VTK_PLUGIN
  loaded = karst_i_plugin_table(KARST_I_VTK_PLUGIN, KARST_I_VTK_ENTRY, 0, KARST_I_VTK_API_VERSION,
                                load_error, sizeof load_error);
#else
  loaded = karst_i_vtk_plugin_api(); /* a static libkarst holds the shim */
#endif
}

const karst_i_vtk_api_t *karst_i_vtk_load(char *why, size_t why_size) {
  if (pthread_once(&once, load) != 0)
    snprintf(load_error, sizeof load_error, "pthread_once failed");
  if (!loaded && why && why_size > 0) snprintf(why, why_size, "%s", load_error);
  return loaded;
}

/* The table, or NULL with the error set on @p ctx, naming @p path. */
static const karst_i_vtk_api_t *api_for(karst_ctx_t *ctx, const char *path) {
  char why[1024];
  const karst_i_vtk_api_t *api = karst_i_vtk_load(why, sizeof why);
  if (!api)
    karst_set_error(ctx, KARST_EEXTERNAL, "%s: VTK is needed and could not be loaded: %s",
                    path ? path : "(no file)", why);
  return api;
}

karst_error_t karst_vtk_read_network(karst_ctx_t *ctx, const char *path, karst_network_t *net) {
  const karst_i_vtk_api_t *api = api_for(ctx, path);
  return api ? api->read_network(ctx, path, net) : KARST_EEXTERNAL;
}

karst_error_t karst_vtk_write_image(karst_ctx_t *ctx, const char *path, const int dims[3],
                                    const double origin[3], const double spacing[3],
                                    const float *values, const char *name) {
  const karst_i_vtk_api_t *api = api_for(ctx, path);
  return api ? api->write_image(ctx, path, dims, origin, spacing, values, name) : KARST_EEXTERNAL;
}

karst_error_t karst_vtk_write_pvd(karst_ctx_t *ctx, const char *path, int n,
                                  const char *const *files) {
  const karst_i_vtk_api_t *api = api_for(ctx, path);
  return api ? api->write_pvd(ctx, path, n, files) : KARST_EEXTERNAL;
}

/* vtp_check.c's decompression runs inside a read, once the plugin is open. */
int karst_i_vtk_uncompress(int compressor, const unsigned char *in, size_t in_len,
                           unsigned char *out, size_t out_len) {
  const karst_i_vtk_api_t *api = karst_i_vtk_load(NULL, 0);
  return api ? api->uncompress(compressor, in, in_len, out, out_len) : -1;
}

karst_error_t karst_i_vtkref_write_network(karst_ctx_t *ctx, const char *path,
                                           const karst_network_t *net) {
  const karst_i_vtk_api_t *api = api_for(ctx, path);
  return api ? api->ref_write_network(ctx, path, net) : KARST_EEXTERNAL;
}

karst_error_t karst_i_vtkref_write_samples(karst_ctx_t *ctx, const char *path,
                                           const karst_samples_t *s) {
  const karst_i_vtk_api_t *api = api_for(ctx, path);
  return api ? api->ref_write_samples(ctx, path, s) : KARST_EEXTERNAL;
}

karst_error_t karst_i_vtkref_write_mesh(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m) {
  const karst_i_vtk_api_t *api = api_for(ctx, path);
  return api ? api->ref_write_mesh(ctx, path, m) : KARST_EEXTERNAL;
}

karst_error_t karst_i_vtkref_write_mesh_arrays(karst_ctx_t *ctx, const char *path,
                                               const karst_mesh_t *m, int n_arrays,
                                               const char *const *names,
                                               const int *const *arrays) {
  const karst_i_vtk_api_t *api = api_for(ctx, path);
  return api ? api->ref_write_mesh_arrays(ctx, path, m, n_arrays, names, arrays) : KARST_EEXTERNAL;
}

karst_error_t karst_i_vtkref_write_polydata(karst_ctx_t *ctx, const char *path,
                                            const karst_polydata_t *pd) {
  const karst_i_vtk_api_t *api = api_for(ctx, path);
  return api ? api->ref_write_polydata(ctx, path, pd) : KARST_EEXTERNAL;
}
