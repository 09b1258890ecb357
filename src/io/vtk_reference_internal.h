/* VTK's own writers of the PolyData files that src/io/write_vtp.c writes without VTK (through
 * vtkXMLPolyDataWriter, src/io/vtk_shim.cpp), kept as the reference that
 * tests/unit/test_vtp_write.c compares karst's files with, byte for byte. Same arguments,
 * checks and messages as the functions of include/karst/vtk.h of the same names. */
#ifndef KARST_VTK_REFERENCE_INTERNAL_H
#define KARST_VTK_REFERENCE_INTERNAL_H

#include "karst/vtk.h"

#ifdef __cplusplus
extern "C" {
#endif

karst_error_t karst_i_vtkref_write_network(karst_ctx_t *ctx, const char *path,
                                           const karst_network_t *net);
karst_error_t karst_i_vtkref_write_samples(karst_ctx_t *ctx, const char *path,
                                           const karst_samples_t *s);
karst_error_t karst_i_vtkref_write_mesh(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m);
karst_error_t karst_i_vtkref_write_mesh_arrays(karst_ctx_t *ctx, const char *path,
                                               const karst_mesh_t *m, int n_arrays,
                                               const char *const *names,
                                               const int *const *arrays);
karst_error_t karst_i_vtkref_write_polydata(karst_ctx_t *ctx, const char *path,
                                            const karst_polydata_t *pd);

#ifdef __cplusplus
}
#endif
#endif
