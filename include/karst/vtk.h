/**
 * @file vtk.h
 * @brief VTK XML files for ParaView. The PolyData files (.vtp) are written by
 *        karst itself (src/io/write_vtp.c: the bytes VTK 9.1's writer makes);
 *        reading them, and the .vti and .pvd writers, go through VTK
 *        (src/io/vtk_shim.cpp, a plugin opened on first use). Files are
 *        written with inline binary data (ParaView 5.11 on Debian reads 0
 *        points from appended mode), to a temporary name and renamed into place.
 */
#ifndef KARST_VTK_H
#define KARST_VTK_H

#include "karst/common.h"
#include "karst/graph.h"
#include "karst/network.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Write a network as .vtp polylines (one 2-point line cell per edge, in edge
 * order, so cell data maps 1:1 to edges), with every node attribute as point
 * data and every edge attribute as cell data (integer attributes as Int32,
 * others Float64, ncomp components), node labels as a string array "label"
 * when present, and the CRS / title as field data. Field data also carries
 * the string arrays "tunnel_type_names" and "node_kind_names" (value i names
 * code i) so a ParaView user can read the integer codes, and "versions" (one
 * "name version" string per component of karst_versions()), as every writer
 * here does.
 *
 * Every writer here states what each point and cell array means (include/karst/arrays.h):
 * its unit as the information key vtkDataArray::UNITS_LABEL, a row (array, unit, meaning)
 * of the 3-component field-data string table "array_units", and for a categorical array
 * the field-data array naming its categories ("vadose_names", ...); docs/arrays.md.
 */
karst_error_t karst_vtk_write_network(karst_ctx_t *ctx, const char *path,
                                      const karst_network_t *net);
/**
 * Read a .vtp written by karst (or any PolyData with lines) into @p net:
 * points become nodes, a polyline of k points becomes k - 1 consecutive
 * edges (its cell data repeated on each), numeric point/cell arrays become
 * node/edge attributes, and "label", "crs" and "title" are restored.
 * @p net must be initialised; it is replaced on success and untouched on
 * failure. Errors (missing, truncated or foreign files) name the file.
 */
karst_error_t karst_vtk_read_network(karst_ctx_t *ctx, const char *path, karst_network_t *net);

/**
 * Write a sample cloud as .vtp vertices with a "source" Int32 point array
 * (karst_sample_source_t), the names of the sources in field data
 * ("source_names") and "n_key_points".
 */
karst_error_t karst_vtk_write_samples(karst_ctx_t *ctx, const char *path, const karst_samples_t *s);

/** A triangle mesh with an optional per-triangle integer label. */
typedef struct karst_mesh {
  karst_int_t n_vertices, n_triangles;
  double *xyz;                /**< 3 * n_vertices */
  karst_int_t *tri;           /**< 3 * n_triangles, counter-clockwise seen from outside */
  int *tri_label;             /**< per-triangle label (e.g. tunnel type) or NULL */
  const char *tri_label_name; /**< name of that cell array (e.g. "tunnel_type"); NULL: "label" */
  int *tri_feature;           /**< per-triangle "feature" (0 wall, 1 speleothem, -1 none) or NULL */
} karst_mesh_t;

/** Write a triangle mesh as .vtp polygons. */
karst_error_t karst_vtk_write_mesh(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m);
/** The same with @p n_arrays further Int32 cell arrays @p arrays named @p names (one value per
 *  triangle each), e.g. block_id and block_type. */
karst_error_t karst_vtk_write_mesh_arrays(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m,
                                          int n_arrays, const char *const *names,
                                          const int *const *arrays);

/** Polygons with integer cell arrays and field-data string lists (karst_vtk_write_polydata). */
typedef struct karst_polydata {
  karst_int_t n_points;
  const double *xyz; /**< 3 * n_points */
  karst_int_t n_polys;
  const karst_int_t *offsets; /**< n_polys + 1: polygon c is conn[offsets[c] .. offsets[c + 1]) */
  const karst_int_t *conn;
  int n_cell_arrays;
  const char *const *cell_array_names;
  const int *const *cell_arrays; /**< n_cell_arrays arrays of n_polys values */
  int n_strings;
  const karst_strings_t *strings; /**< field-data string lists (e.g. "feature_names") */
  const char *role; /**< the kind of file ("geology"), for the units of its arrays (arrays.h) */
} karst_polydata_t;

/** Write polygons as .vtp (inline binary), atomically. */
karst_error_t karst_vtk_write_polydata(karst_ctx_t *ctx, const char *path,
                                       const karst_polydata_t *pd);

/**
 * Write a scalar field on a regular grid as .vti image data: dims[3] points,
 * origin and spacing in metres, values x fastest, named @p name.
 */
karst_error_t karst_vtk_write_image(karst_ctx_t *ctx, const char *path, const int dims[3],
                                    const double origin[3], const double spacing[3],
                                    const float *values, const char *name);

/**
 * Write a ParaView collection (.pvd) listing @p n files (paths relative to
 * the .pvd; absolute paths are refused so the collection can be moved) as
 * time steps 0 .. n-1, XML-escaped, atomically.
 */
karst_error_t karst_vtk_write_pvd(karst_ctx_t *ctx, const char *path, int n,
                                  const char *const *files);

#ifdef __cplusplus
}
#endif
#endif
