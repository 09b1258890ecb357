/* VTK XML PolyData (.vtp) written without VTK (vtp_write.c), for the writers of
 * include/karst/vtk.h that karst generate, karst ensemble and the mesh and block commands call.
 *
 * Linking VTK costs every process about 20 ms at start-up on the machines karst is measured
 * on (about 620 page faults and the relocations of its C++ libraries), a sixth of a
 * Karst-Synthesis-sized run. The files are the ones VTK 9.1's vtkXMLPolyDataWriter writes
 * with karst's settings (inline binary, zlib level 1 in 32 KiB blocks, UInt64 headers),
 * byte for byte: tests/unit/test_vtp_write.c compares the two writers on the same data. */
#ifndef KARST_VTP_WRITE_INTERNAL_H
#define KARST_VTP_WRITE_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The zlib level of every file karst writes, by its writer and by VTK's (src/io/vtk_shim.cpp).
 *  VTK's default is 5: at level 5 compression took about a tenth of a small run
 *  (Karst-Synthesis's rectilinear scene, bench_peers); level 1 makes the files about 3 % larger
 *  (looping cave network.vtp 733 -> 751 kB) with the same data. */
#define KARST_I_VTP_ZLIB_LEVEL 1

typedef enum {
  KARST_I_VTP_INT32 = 0,
  KARST_I_VTP_INT64 = 1,
  KARST_I_VTP_FLOAT64 = 2,
  KARST_I_VTP_STRING = 3
} karst_i_vtp_type_t;

/** One array of field, point or cell data, or the points. */
typedef struct karst_i_vtp_array {
  const char *name;
  karst_i_vtp_type_t type;
  int ncomp;                      /**< components, >= 1 */
  const char *const *comp_names;  /**< ncomp names (field-data string tables), or NULL */
  karst_int_t n;                  /**< tuples */
  const void *data;               /**< n ncomp values: int32_t, int64_t, double, or for strings
                                       const char *const * (NULL entries written as "") */
  const char *units;              /**< the information key UNITS_LABEL, or NULL */
} karst_i_vtp_array_t;

/** Cell kinds of a PolyData piece, in the file's order. */
enum { KARST_I_VTP_VERTS = 0, KARST_I_VTP_LINES, KARST_I_VTP_STRIPS, KARST_I_VTP_POLYS };

typedef struct karst_i_vtp_polydata {
  karst_int_t n_points;
  const double *xyz; /**< 3 n_points */
  /** Cells of each kind: n_cells[k] cells, cell c holding conn[k][ends[k][c - 1] .. ends[k][c])
   *  (ends[k][-1] taken as 0): VTK's XML "offsets" are these end offsets. */
  karst_int_t n_cells[4];
  const int64_t *ends[4], *conn[4];
  int n_field, n_point, n_cell;
  const karst_i_vtp_array_t *field, *point, *cell;
  const char *point_scalars, *cell_scalars; /**< active scalars' names, or NULL */
} karst_i_vtp_polydata_t;

/**
 * Write @p pd to @p path: the whole file is made in memory, written to a temporary name beside
 * @p path and renamed into place, so a failure leaves no file behind.
 * @return KARST_SUCCESS, KARST_ENOMEM, KARST_EIO (naming @p path), KARST_EINTERRUPTED.
 * Time complexity: O(size of the data).
 */
karst_error_t karst_i_vtp_write(karst_ctx_t *ctx, const char *path,
                                const karst_i_vtp_polydata_t *pd);

/**
 * @p v as VTK 9.1 writes a double in an XML attribute (vtkNumberToString: double-conversion's
 * shortest round-trip digits in ECMAScript notation: "0.5", "1e+299", "1e-7", "Infinity"),
 * into @p buf (at least 32 bytes). @return the length.
 */
int karst_i_vtp_format_shortest(double v, char *buf);

/**
 * Decompress one block of a VTK XML file with VTK's own decompressors (compressor 1: zlib,
 * 2: LZ4, 3: LZMA), for the check of vtp_check.c: through the VTK plugin
 * (io/vtk_api_internal.h). @return 0 when the block gives exactly @p out_len bytes, else -1.
 */
int karst_i_vtk_uncompress(int compressor, const unsigned char *in, size_t in_len,
                           unsigned char *out, size_t out_len);

#ifdef __cplusplus
}
#endif
#endif
