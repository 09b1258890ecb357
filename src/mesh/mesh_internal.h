/* Private pieces shared by src/mesh/ (and its tests): an int64 hash map and
 * the independent CGAL check of a mesh (src/geometry/cgal_shim.cpp). */
#ifndef KARST_MESH_INTERNAL_H
#define KARST_MESH_INTERNAL_H

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Open-addressing map from non-negative int64 keys to int64 values. */
typedef struct karst_i_hmap {
  karst_int_t *keys, *vals;
  karst_int_t cap, n;
} karst_i_hmap_t;

int karst_i_hmap_init(karst_i_hmap_t *h, karst_int_t expected);
void karst_i_hmap_destroy(karst_i_hmap_t *h);
/* 1 when @p key is present. */
int karst_i_hmap_find(const karst_i_hmap_t *h, karst_int_t key);
int karst_i_hmap_find_or_insert(karst_i_hmap_t *h, karst_int_t key, karst_int_t val,
                                karst_int_t *out);

/* What CGAL says about a triangle soup (CGAL::Polygon_mesh_processing). */
typedef struct karst_i_cgal_report {
  int is_polygon_mesh; /* is_polygon_soup_a_polygon_mesh: manifold and consistently oriented */
  int closed;          /* CGAL::is_closed */
  int outward;         /* PMP::is_outward_oriented */
  double volume;       /* PMP::volume (0 unless closed) */
} karst_i_cgal_report_t;

/* Build a CGAL Surface_mesh from the soup and check it. Returns 0, or -1 when
 * CGAL threw (message in err, which may be NULL). */
int karst_i_cgal_check_mesh(const double *xyz, karst_int_t n_vertices, const karst_int_t *tri,
                            karst_int_t n_triangles, karst_i_cgal_report_t *rep, char *err,
                            size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
