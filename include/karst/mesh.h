/**
 * @file mesh.h
 * @brief Polygonization of a construction tree (include/karst/implicit.h)
 *        into a closed, 2-manifold, consistently oriented triangle mesh, and
 *        the mesh writers (.vtp through karst_vtk_write_mesh, binary .ply,
 *        binary .stl), all written atomically.
 *
 * The mesh type karst_mesh_t is declared in karst/vtk.h. Triangles are
 * counter-clockwise seen from outside the solid (the side where the field is
 * positive); each carries the tunnel type of the primitive that decided the
 * field at its inside corner (-1 for terrain and the clipping box) and its
 * feature (KARST_SDF_FEATURE_WALL, KARST_SDF_FEATURE_SPELEOTHEM; -1 there).
 */
#ifndef KARST_MESH_H
#define KARST_MESH_H

#include "karst/common.h"
#include "karst/implicit.h"
#include "karst/vtk.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Empty mesh (caller-owned storage). */
void karst_mesh_init(karst_mesh_t *m);
/** Release the arrays a mesh holds (xyz, tri, tri_label, tri_feature) and leave it empty. */
void karst_mesh_destroy(karst_mesh_t *m);

typedef struct karst_polygonize_stats {
  karst_int_t cells[3];  /**< grid size in cells */
  karst_int_t n_tiles;   /**< parallel work units (32³ cells) */
  karst_int_t n_blocks;  /**< blocks tested against the Lipschitz bound */
  karst_int_t n_skipped; /**< of which proved empty and skipped */
  karst_int_t n_cells;   /**< cells polygonized */
  karst_int_t n_evals;   /**< field evaluations */
  karst_int_t n_vertices, n_triangles;
} karst_polygonize_stats_t;

/**
 * Vertices lie on grid edges at a fraction t of the edge from its lower end,
 * clamped to [m, 1 - m] with this margin m. Where the surface passes through
 * (or within rounding of) a grid point, the unclamped vertices of all edges
 * meeting there would coincide, making zero-area triangles (300 of 15 840
 * for a sphere of radius 3 m centred on a 0.25 m grid). With the margin,
 * vertices sharing a grid point stay at least m h sin 35° = 0.0058 h apart
 * (2.9 mm at 0.5 m), which float32 (STL) keeps apart too. The surface moves by
 * at most m √3 h (8.7 mm at 0.5 m) there; the topology does not change.
 */
#define KARST_MESH_EDGE_MARGIN 0.01

/**
 * Polygonize the zero set of the root of @p sdf inside @p box (lo, hi) on a
 * grid of @p voxel metres: marching tetrahedra on the Kuhn split of every
 * cube (six tetrahedra around the main diagonal, the same in every cell, so
 * neighbouring cells agree on their shared faces), vertices shared by the
 * grid edge they lie on. The field is intersected with the box shrunk by
 * half a voxel, so the mesh is closed where the solid leaves the box. Blocks
 * whose centre value exceeds their half diagonal are skipped (1-Lipschitz:
 * no surface inside), so the cost grows with the surface area. Work is split
 * in tiles over ctx->nthreads threads; the output does not depend on the
 * thread count. Progress is reported as stage "polygonize".
 * @param out  an initialised mesh, filled (emptied first)
 * @param stats may be NULL
 * @return KARST_SUCCESS; KARST_EINVAL (no root, bad box or voxel);
 *         KARST_ERANGE (grid too large or box thinner than two voxels);
 *         KARST_ENOMEM; KARST_EINTERRUPTED. On failure @p out is empty.
 * Time complexity: O(surface cells × field cost + blocks).
 */
karst_error_t karst_mesh_polygonize(karst_ctx_t *ctx, const karst_sdf_t *sdf, const double box[6],
                                    double voxel, karst_mesh_t *out,
                                    karst_polygonize_stats_t *stats);

/**
 * The grid karst_mesh_polygonize and karst_mesh_sample use for @p box and
 * @p voxel, without any field evaluation, so that sizes can be checked
 * before the work: @p cells receives ceil(length / voxel) per axis (grid
 * points: cells + 1). @return KARST_SUCCESS; KARST_EINVAL (bad box or voxel);
 * KARST_ERANGE (box thinner than two voxels, or more than 2^21 cells along
 * an axis or 2^46 in all).
 */
karst_error_t karst_mesh_grid(karst_ctx_t *ctx, const double box[6], double voxel,
                              karst_int_t cells[3]);

/**
 * Sample the field of the root of @p sdf, intersected with the box as in
 * karst_mesh_polygonize, at the grid points of the same grid; @p values
 * (allocated, caller frees) is x fastest. At most KARST_MESH_SAMPLE_MAX points.
 */
#define KARST_MESH_SAMPLE_MAX ((karst_int_t)1 << 28)
karst_error_t karst_mesh_sample(karst_ctx_t *ctx, const karst_sdf_t *sdf, const double box[6],
                                double voxel, int dims[3], double origin[3], float **values);

/** Write the sampled field as .vti image data ("sdf" point array) for ParaView's contour filter. */
karst_error_t karst_mesh_write_sdf(karst_ctx_t *ctx, const char *path, const karst_sdf_t *sdf,
                                   const double box[6], double voxel);

/** Write by extension: .vtp (karst_vtk_write_mesh), .ply, .stl (case-insensitive). */
karst_error_t karst_mesh_write(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m);
/** Binary little-endian PLY: double x, y, z; int vertex indices; int tunnel_type and int feature
 *  per face (each when present). */
karst_error_t karst_mesh_write_ply(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m);
/**
 * Binary STL. The format stores float32 only (24-bit mantissa: 6 cm steps at
 * a UTM easting of 6e5 m, 0.5 m at a northing of 5e6 m), so far from the
 * origin the vertices are written minus karst_mesh_stl_origin; the header
 * starts "karst origin x=X y=Y z=Z" (metres) for the reader to add back.
 */
karst_error_t karst_mesh_write_stl(karst_ctx_t *ctx, const char *path, const karst_mesh_t *m);

/** Coordinates within ±this many metres are written to STL as they are
 *  (float32 rounds them by at most 2^-24 × 1000 m = 0.06 mm). */
#define KARST_MESH_STL_SMALL 1000.0
/** STL origins are multiples of this many metres (readable, exact in text). */
#define KARST_MESH_STL_ORIGIN_STEP 100.0
/**
 * The origin karst_mesh_write_stl subtracts: per axis, 0 when every
 * coordinate lies within ±KARST_MESH_STL_SMALL, else the smallest coordinate
 * rounded down to a multiple of KARST_MESH_STL_ORIGIN_STEP. Along a shifted
 * axis the written coordinates lie in [0, extent + 100 m) and are rounded by
 * at most 2^-24 × that (0.07 mm for a 1 km mesh). Empty mesh: (0, 0, 0).
 */
void karst_mesh_stl_origin(const karst_mesh_t *m, double origin[3]);

/** Enclosed volume by the divergence theorem (positive for outward orientation). */
double karst_mesh_volume(const karst_mesh_t *m);

typedef struct karst_mesh_check {
  karst_int_t boundary_edges;    /**< directed edges without their reverse */
  karst_int_t nonmanifold_edges; /**< directed edges used by more than one triangle */
  karst_int_t degenerate;        /**< triangles with a repeated vertex index */
} karst_mesh_check_t;

/**
 * Combinatorial check: the mesh is closed and consistently oriented exactly
 * when every directed edge appears once and its reverse once (all three
 * counts zero). Time: O(T log T).
 */
karst_error_t karst_mesh_check(karst_ctx_t *ctx, const karst_mesh_t *m, karst_mesh_check_t *res);

#ifdef __cplusplus
}
#endif
#endif /* KARST_MESH_H */
