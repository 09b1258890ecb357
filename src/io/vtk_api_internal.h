/* What karst still does with VTK, loaded on first use (src/io/vtk_api.c).
 *
 * VTK 9.1's libraries cost every process that links them about 20 ms at start-up on the project
 * machine (an empty program linked with VTK's CommonCore, CommonDataModel, CommonExecutionModel
 * and IOXML starts in 24.7 ms, without them in 3.2 ms: about 620 page faults and the relocations
 * of its C++ libraries), a sixth of a Karst-Synthesis-sized run. karst writes its .vtp files
 * itself (src/io/write_vtp.c), so VTK is needed only to read .vtp files, to write .vti images and
 * .pvd collections, and as the reference writer of the tests. Those calls live in a plugin,
 * libkarst_vtk.so (src/io/vtk_shim.cpp, linked with VTK), built and installed next to libkarst,
 * which karst_i_vtk_load opens with dlopen the first time one of them is made. A static libkarst
 * (the fuzzing build) holds the shim itself and calls it directly. */
#ifndef KARST_VTK_API_INTERNAL_H
#define KARST_VTK_API_INTERNAL_H

#include <stddef.h>

#include "karst/vtk.h"

#ifdef __cplusplus
extern "C" {
#endif

/** File name of the plugin, in libkarst's own directory (a test builds the loader with a name
 *  that does not exist). */
#ifndef KARST_I_VTK_PLUGIN
#define KARST_I_VTK_PLUGIN "libkarst_vtk.so"
#endif
/** The plugin's one exported symbol: a function returning its table. */
#define KARST_I_VTK_ENTRY "karst_i_vtk_plugin_api"
/** Plugin interface version: the table's layout; a plugin of another version is refused. */
#define KARST_I_VTK_API_VERSION 1

/** The calls into VTK, with the arguments and results of the functions they serve (vtk.h,
 *  io/vtk_reference_internal.h, and karst_i_vtk_uncompress of vtp_check.c). */
typedef struct {
  int version; /* KARST_I_VTK_API_VERSION */
  karst_error_t (*read_network)(karst_ctx_t *ctx, const char *path, karst_network_t *net);
  karst_error_t (*write_image)(karst_ctx_t *ctx, const char *path, const int dims[3],
                               const double origin[3], const double spacing[3],
                               const float *values, const char *name);
  karst_error_t (*write_pvd)(karst_ctx_t *ctx, const char *path, int n, const char *const *files);
  int (*uncompress)(int compressor, const unsigned char *in, size_t in_len, unsigned char *out,
                    size_t out_len);
  karst_error_t (*ref_write_network)(karst_ctx_t *ctx, const char *path,
                                     const karst_network_t *net);
  karst_error_t (*ref_write_samples)(karst_ctx_t *ctx, const char *path, const karst_samples_t *s);
  karst_error_t (*ref_write_mesh)(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m);
  karst_error_t (*ref_write_mesh_arrays)(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m,
                                         int n_arrays, const char *const *names,
                                         const int *const *arrays);
  karst_error_t (*ref_write_polydata)(karst_ctx_t *ctx, const char *path,
                                      const karst_polydata_t *pd);
} karst_i_vtk_api_t;

/** The plugin's table (defined in vtk_shim.cpp). */
const karst_i_vtk_api_t *karst_i_vtk_plugin_api(void);

/**
 * Open the plugin once per process (thread-safe); later calls return the first call's result.
 * @return the table, or NULL with the reason (dlopen's, or a version mismatch) in @p why.
 */
const karst_i_vtk_api_t *karst_i_vtk_load(char *why, size_t why_size);

#ifdef __cplusplus
}
#endif
#endif
