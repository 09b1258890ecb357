/* The C side of the CGAL shim (src/geometry/cgal_shim.cpp) used by the rock
 * blocks (src/blocks/): convex hulls and intersections of half-spaces. The
 * mesh check of the same shim is declared in src/mesh/mesh_internal.h. */
#ifndef KARST_GEOMETRY_INTERNAL_H
#define KARST_GEOMETRY_INTERNAL_H

#include "karst/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A convex polytope: its triangulated boundary (counter-clockwise seen from
 * outside), the half-spaces u.p <= d that support a face (u unit), and the
 * volume CGAL::Polygon_mesh_processing::volume measures. Arrays are malloc'd
 * by the shim; release with karst_i_polytope_destroy. */
typedef struct karst_i_polytope {
  karst_int_t n_vertices, n_triangles, n_planes;
  double *xyz;      /* 3 n_vertices */
  karst_int_t *tri; /* 3 n_triangles */
  double *planes;   /* 4 n_planes: ux, uy, uz, d */
  double volume;
} karst_i_polytope_t;

void karst_i_polytope_destroy(karst_i_polytope_t *p);

/* The planes of the faces of the convex hull of @p n >= 4 points that span a
 * volume (CGAL::convex_hull_3), as outward half-spaces u.p <= d, u unit; one
 * per hull triangle (coplanar triangles repeat their plane). *planes is
 * malloc'd. Returns 0, or -1 with a message in err (CGAL threw, or out of
 * memory). */
int karst_i_cgal_hull_planes(const double *xyz, karst_int_t n, double **planes,
                             karst_int_t *n_planes, char *err, size_t errlen);

/* The intersection of @p m half-spaces u.p <= d (4 doubles each) containing
 * @p interior strictly (CGAL::halfspace_intersection_3), bounded. Planes that
 * support a face are those with at least three vertices within @p tol metres.
 * Returns 0, or -1 with a message in err. */
int karst_i_cgal_halfspaces(const double *planes, karst_int_t m, const double interior[3],
                            double tol, karst_i_polytope_t *out, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
