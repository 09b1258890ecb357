/**
 * @file implicit.h
 * @brief Implicit conduit geometry (Paris et al. 2021, §6 and Appendices A–C):
 *        a construction tree of 1-Lipschitz signed-distance bounds whose leaves
 *        are skeletal primitives (sweeps of piecewise-quadratic cross-sections,
 *        ellipsoids, spheres, the terrain heightfield, boxes) and whose inner
 *        nodes are Boolean, blending, noise and warping operators.
 *
 * Sign convention (one, everywhere): a node's field is NEGATIVE INSIDE the
 * solid it describes and positive outside. The terrain's solid is the
 * bedrock (f < 0 below the ground), a conduit primitive's solid is the void
 * of the conduit, and the final model "terrain minus conduits" is the rock:
 * negative in rock, positive in air and in the caves — the paper's "positive
 * outside of the bedrock and negative inside" (§6).
 *
 * Every field is 1-Lipschitz: |f(p) - f(q)| <= |p - q|. Hence |f(p)| is a
 * lower bound of the distance from p to the surface, which the polygonizer
 * and the bounding-volume hierarchy use to skip empty space.
 *
 * Every node also satisfies f(p) >= sdbox(p) where sdbox is the exact signed
 * distance to the node's bounding box (each node's value is clamped from
 * below by it, which leaves the zero set unchanged because the solid lies
 * strictly inside the box). That is what makes box distances valid lower
 * bounds in the hierarchy.
 */
#ifndef KARST_IMPLICIT_H
#define KARST_IMPLICIT_H

#include "karst/common.h"
#include "karst/image.h"
#include "karst/network.h"
#include "karst/scenario.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------ */
/* Cross-sections: closed curves of quadratic Bezier pieces (Appendix C).    */
/* ------------------------------------------------------------------------ */

/** Most quadratic pieces a cross-section may have. */
#define KARST_SECTION_MAX_PIECES 16

/**
 * A closed piecewise-quadratic curve in the cross-section plane, coordinates
 * (across, up) in units of the conduit radius. Piece k has the control points
 * cp[2k] (on the curve), cp[2k+1] (off the curve) and cp[(2k+2) mod 2n].
 * The curve must be simple (no self-intersection); its orientation does not
 * matter (inside is decided by crossing count).
 */
typedef struct karst_section {
  int n;                                      /**< number of pieces, 2..KARST_SECTION_MAX_PIECES */
  double cp[2 * KARST_SECTION_MAX_PIECES][2]; /**< control points */
} karst_section_t;

/**
 * The unit cross-section of a tunnel type (Paris et al. 2021, Fig. 11/12):
 * every built-in section has 8 pieces so that two of them can be interpolated
 * control point by control point. Chambers get the tube section (they are
 * modelled as ellipsoids, not sweeps).
 */
karst_error_t karst_section_for_type(karst_ctx_t *ctx, int tunnel_type, karst_section_t *out);
/** Check a section: 2..16 pieces, finite control points, non-zero area. */
karst_error_t karst_section_check(karst_ctx_t *ctx, const karst_section_t *s);
/** Signed in-plane distance to the section: negative inside (Appendix C). */
double karst_section_distance(const karst_section_t *s, const double q[2]);
/** Exact enclosed area (Green's theorem on the quadratic pieces), in squared radius units. */
double karst_section_area(const karst_section_t *s);
/** Interpolate two sections with the same piece count: (1-t) a + t b, control point-wise. */
karst_error_t karst_section_lerp(karst_ctx_t *ctx, const karst_section_t *a,
                                 const karst_section_t *b, double t, karst_section_t *out);

/** Most sections of a mixture. */
#define KARST_SECTION_MIX_MAX 4
/** Cells per side of the grid on which karst_section_mix_area integrates a mixture. */
#define KARST_SECTION_MIX_AREA_CELLS 64

/**
 * A weighted mixture of unit sections, the cross-section between two
 * shapes: its in-plane field is Σ_k w_k d_k(q) / Σ_k w_k with d_k the signed
 * distance to section k. A convex combination of 1-Lipschitz fields is
 * 1-Lipschitz, and its zero set morphs from one shape to the other with no
 * fold (control-point interpolation of differently built sections folds).
 */
typedef struct karst_section_mix {
  int n; /**< 1..KARST_SECTION_MIX_MAX */
  karst_section_t section[KARST_SECTION_MIX_MAX];
  double weight[KARST_SECTION_MIX_MAX]; /**< > 0 */
} karst_section_mix_t;

/** The mixture's in-plane field at @p q (unit coordinates). O(pieces). */
double karst_section_mix_distance(const karst_section_mix_t *m, const double q[2]);
/**
 * Area enclosed by the mixture (unit coordinates): Green's theorem for one
 * section; else the area where the field, interpolated linearly on two
 * triangles per cell of a grid of KARST_SECTION_MIX_AREA_CELLS² cells over the
 * sections' extent, is negative (second-order: 0.02 % for the tube).
 */
double karst_section_mix_area(const karst_section_mix_t *m);

/* ------------------------------------------------------------------------ */
/* The construction tree.                                                    */
/* ------------------------------------------------------------------------ */

typedef enum {
  KARST_SDF_SPHERE = 0,
  KARST_SDF_ELLIPSOID,
  KARST_SDF_SWEEP,
  KARST_SDF_TERRAIN,
  KARST_SDF_BOX,
  KARST_SDF_UNION,
  KARST_SDF_INTERSECTION,
  KARST_SDF_DIFFERENCE,
  KARST_SDF_BLEND,
  KARST_SDF_NOISE,
  KARST_SDF_REVOLVE,
  KARST_SDF_PLANE,
  KARST_SDF_SMOOTH_INTERSECTION,
  KARST_SDF_THICK,
  KARST_SDF_EXTERNAL,
  KARST_SDF_WARP,
  KARST_SDF_DETAILS,
  KARST_SDF_ROUND_CONE,
  KARST_SDF_RESCALE,
  KARST_SDF_KIND_COUNT
} karst_sdf_kind_t;

/** Label of nodes that are no conduit (terrain, boxes): written as tunnel_type -1. */
#define KARST_SDF_NO_LABEL (-1)

/** Features of a conduit's surface, the mesh's per-triangle "feature" array. */
#define KARST_SDF_FEATURE_WALL 0
#define KARST_SDF_FEATURE_SPELEOTHEM 1
/** A primitive's label: its tunnel type (0..15) and feature; KARST_SDF_NO_LABEL stays -1. */
#define KARST_SDF_LABEL(type, feature) ((type) + 16 * (feature))
/** Tunnel type of a label (-1 for KARST_SDF_NO_LABEL). */
#define KARST_SDF_LABEL_TYPE(label) ((label) < 0 ? -1 : (label) % 16)
/** Feature of a label (-1 for KARST_SDF_NO_LABEL). */
#define KARST_SDF_LABEL_FEATURE(label) ((label) < 0 ? -1 : (label) / 16)

/** Opaque construction tree (nodes are referred to by index). */
typedef struct karst_sdf karst_sdf_t;

/** Allocate an empty tree. */
karst_error_t karst_sdf_create(karst_ctx_t *ctx, karst_sdf_t **out);
/** Release a tree (NULL allowed). */
void karst_sdf_free(karst_sdf_t *sdf);

/** Sphere of centre @p c and radius @p r > 0 (exact distance). */
karst_error_t karst_sdf_sphere(karst_ctx_t *ctx, karst_sdf_t *sdf, const double c[3], double r,
                               int label, karst_int_t *node);
/**
 * Ellipsoid of centre @p c, orthonormal axes @p axes (rows) and semi-axes
 * @p radii (all > 0). Its field is the 1-Lipschitz bound
 * (|D^-1 R (p - c)| - 1) min(radii).
 */
karst_error_t karst_sdf_ellipsoid(karst_ctx_t *ctx, karst_sdf_t *sdf, const double c[3],
                                  const double axes[3][3], const double radii[3], int label,
                                  karst_int_t *node);

/** End of a sweep: flat cap perpendicular to the segment, or a mitre plane. */
typedef struct karst_sweep_end {
  int mitre; /**< 0: flat cap; 1: cut by the plane through the end point with normal @c n */
  double
      n[3]; /**< outward unit normal of the mitre plane (n . u must be > 0.1 at b, < -0.1 at a) */
} karst_sweep_end_t;

/**
 * Sweep of @p section (scaled by @p radius) along the segment a–b
 * (Appendix B). The section's "up" axis is @p up projected orthogonally to
 * the segment (world z when NULL; world y for vertical segments). @p ends
 * may be NULL (flat caps at both ends).
 */
karst_error_t karst_sdf_sweep(karst_ctx_t *ctx, karst_sdf_t *sdf, const double a[3],
                              const double b[3], const karst_section_t *section, double radius,
                              const double up[3], const karst_sweep_end_t ends[2], int label,
                              karst_int_t *node);
/**
 * Revolution of a section about an axis, cut to a wedge: the bend joint
 * between two sweeps. The section (scaled by @p radius) lies in the plane
 * through @p o spanned by the unit vectors @p side and @p up (its x and y
 * axes); the unit @p axis must lie in that plane. The section is revolved
 * fully about the line (o, axis) and the solid is cut by the two planes through
 * o with outward unit normals @p n[0], @p n[1]. With r, z the distance to and
 * the position along the axis, and x the in-plane direction perpendicular to
 * the axis, the field is
 *     max(radius min(w(( r x + z axis)/radius), w((-r x + z axis)/radius)), n0.(p-o), n1.(p-o)),
 * 1-Lipschitz because (r, z) is a 1-Lipschitz function of p.
 */
karst_error_t karst_sdf_revolve(karst_ctx_t *ctx, karst_sdf_t *sdf, const double o[3],
                                const double axis[3], const double side[3], const double up[3],
                                const karst_section_t *section, double radius, const double n[2][3],
                                int label, karst_int_t *node);

/**
 * A sweep whose cross-section morphs along a–b from mixture @p ma of area
 * @p area_a (m²) at a to @p mb of area @p area_b at b: at axial position l,
 * t = smoothstep(l / |b - a|), the weights are (1 - t) ma + t mb and the
 * mixture is scaled so that its area is (1 - t) area_a + t area_b (tabulated at
 * KARST_I_MORPH_TAB + 1 values of t, linear between). The area therefore
 * varies monotonically, and the ends match a plain sweep of the same
 * section and area exactly. The in-plane field F has |∇_q F| <= 1 and
 * |∂F/∂l| <= β = (1.5/|b - a|)(max|ρ'| P + ρ_max H) (ρ the scale, P the
 * sections' extent, H a bound of |F_a - F_b| in unit coordinates, proof in
 * morph.c); the extrusion of F and the end slab is then
 * K = sqrt(1 + β²/4) + β/2 - Lipschitz and is divided by K.
 * @return KARST_SUCCESS; KARST_EINVAL (bad mixtures, areas, more than
 *         KARST_SECTION_MIX_MAX distinct sections, degenerate segment);
 *         KARST_ENOMEM. Time: O(1) per evaluation and section; building
 *         integrates new mixtures on a grid (cached in the tree).
 */
karst_error_t karst_sdf_sweep_morph(karst_ctx_t *ctx, karst_sdf_t *sdf, const double a[3],
                                    const double b[3], const karst_section_mix_t *ma, double area_a,
                                    const karst_section_mix_t *mb, double area_b,
                                    const double up[3], const karst_sweep_end_t ends[2], int label,
                                    karst_int_t *node);
/**
 * karst_sdf_revolve with a mixture scaled to the enclosed area @p area (m²):
 * the bend joint between two morphing sweeps that meet with this mixture.
 */
karst_error_t karst_sdf_revolve_mix(karst_ctx_t *ctx, karst_sdf_t *sdf, const double o[3],
                                    const double axis[3], const double side[3], const double up[3],
                                    const karst_section_mix_t *m, double area, const double n[2][3],
                                    int label, karst_int_t *node);

/**
 * Terrain heightfield (Appendix A): f = (z - h(x, y)) / sqrt(1 + λ²), negative
 * in the bedrock. The grid is copied. λ is the larger of t->lipschitz and the
 * maximum slope of the bilinear surface computed here from the grid.
 */
karst_error_t karst_sdf_terrain(karst_ctx_t *ctx, karst_sdf_t *sdf, const karst_terrain_t *t,
                                karst_int_t *node);
/** Axis-aligned box [lo, hi] (exact distance). */
karst_error_t karst_sdf_box(karst_ctx_t *ctx, karst_sdf_t *sdf, const double lo[3],
                            const double hi[3], karst_int_t *node);

/** Union (min) of @p n >= 1 nodes, with a bounding-volume hierarchy over the finite ones. */
karst_error_t karst_sdf_union(karst_ctx_t *ctx, karst_sdf_t *sdf, karst_int_t n,
                              const karst_int_t *children, karst_int_t *node);
/** Intersection max(a, b). */
karst_error_t karst_sdf_intersection(karst_ctx_t *ctx, karst_sdf_t *sdf, karst_int_t a,
                                     karst_int_t b, karst_int_t *node);
/** Difference a minus b: max(a, -b). */
karst_error_t karst_sdf_difference(karst_ctx_t *ctx, karst_sdf_t *sdf, karst_int_t a, karst_int_t b,
                                   karst_int_t *node);
/**
 * Smooth blend of a and b over a width @p k > 0 (polynomial smooth minimum,
 * min(a,b) - k h²/4 with h = max(k - |a-b|, 0)/k; its gradient is a convex
 * combination of the children's, so it stays 1-Lipschitz).
 */
karst_error_t karst_sdf_blend(karst_ctx_t *ctx, karst_sdf_t *sdf, karst_int_t a, karst_int_t b,
                              double k, karst_int_t *node);
/**
 * Wall irregularities: f' = (f + A n(p)) / (1 + A Ln), where n is a sparse
 * Gabor noise (Zanni et al. 2012) with |n| <= 1 and Lipschitz constant Ln
 * (proved in noise.c), A = @p amplitude (metres, the largest displacement)
 * and @p wavelength its main wavelength (m). The impulses are a pure function
 * of the cell and a seed drawn from @p rng.
 */
karst_error_t karst_sdf_noise(karst_ctx_t *ctx, karst_sdf_t *sdf, karst_int_t child,
                              double amplitude, double wavelength, karst_rng_t *rng,
                              karst_int_t *node);

/* ------------------------------------------------------------------------ */
/* Convex blocks (Paris et al. 2020, §4.2) and external fields.              */
/* ------------------------------------------------------------------------ */

/**
 * Half-space u.(p - o) <= 0 with outward unit normal @p u (normalised here):
 * the exact signed distance to the plane, 1-Lipschitz, unbounded.
 */
karst_error_t karst_sdf_plane(karst_ctx_t *ctx, karst_sdf_t *sdf, const double o[3],
                              const double u[3], karst_int_t *node);

/**
 * The smooth maximum of Paris et al. 2020, §4.2, in this tree's sign
 * convention: smax_R(a, b) = max(a, b) + R k³/6, k = max(1 - |a - b|/R, 0).
 * It equals max(a, b) when |a - b| >= R, exceeds it by at most R/6, and its
 * gradient is (1 - k²/2) ∇a + (k²/2) ∇b (a >= b), a convex combination:
 * 1-Lipschitz and C¹ (proof in smooth.c). R = 0 gives max(a, b).
 */
double karst_sdf_smooth_max(double a, double b, double R);

/**
 * Smooth intersection of @p n >= 1 children folded from the left,
 * smax_R(... smax_R(f_0, f_1) ..., f_{n-1}) (the operator is not
 * associative; the order is the caller's, as the paper notes). Its solid is
 * inside every child's. @p box, when not NULL, is a box the caller knows to
 * contain the solid (e.g. a convex block's vertices); NULL derives it from
 * the bounded children (unbounded when none is).
 */
karst_error_t karst_sdf_smooth_intersection(karst_ctx_t *ctx, karst_sdf_t *sdf, karst_int_t n,
                                            const karst_int_t *children, double R,
                                            const double box[6], karst_int_t *node);

/**
 * The thick point, segment or polygon of Paris et al. 2020, §4.2 for
 * degenerate clusters: the exact signed distance to the convex hull of @p n
 * points (which must be coplanar within @p flat_tol metres), minus
 * @p radius > 0. One point gives a sphere, collinear points a capsule,
 * coplanar points a flat slab with rounded rims.
 */
karst_error_t karst_sdf_thick(karst_ctx_t *ctx, karst_sdf_t *sdf, karst_int_t n, const double *xyz,
                              double radius, double flat_tol, int label, karst_int_t *node);

/**
 * An external field, evaluated by a callback another module provides (the
 * block replication of src/blocks/). Contract: fn is 1-Lipschitz, negative
 * inside, returns its exact value and label when that value is below @p ub
 * and otherwise any value >= ub, and is thread-safe. @p box (NULL:
 * unbounded) must contain the solid; the field is clamped by it.
 */
typedef double (*karst_sdf_field_fn)(const void *arg, const double p[3], double ub, int *label);
karst_error_t karst_sdf_external(karst_ctx_t *ctx, karst_sdf_t *sdf, karst_sdf_field_fn fn,
                                 const void *arg, const double box[6], int label,
                                 karst_int_t *node);

/* ------------------------------------------------------------------------ */
/* Gradient-based warping (Paris et al. 2020, §4.3; shared with the blocks).  */
/* ------------------------------------------------------------------------ */

/** What the relief d of a warp node is. */
typedef enum {
  KARST_RELIEF_NOISE = 0, /**< procedural value-noise turbulence d(u, v), tri-planar */
  KARST_RELIEF_IMAGE,     /**< a greyscale image tiled over each plane, tri-planar */
  KARST_RELIEF_FUNCTION,  /**< the caller's function d(u, v), tri-planar */
  KARST_RELIEF_FRACTURES, /**< grooves along the planes of fracture families (3-D, no projection) */
  KARST_RELIEF_KIND_COUNT
} karst_relief_kind_t;

/** Most fracture families of a KARST_RELIEF_FRACTURES relief. */
#define KARST_RELIEF_MAX_PLANES 16
/** Most octaves of a KARST_RELIEF_NOISE relief. */
#define KARST_RELIEF_MAX_OCTAVES 8

/**
 * A caller's relief: a value in [-1, 1] at plane coordinates (u, v) in
 * metres, Lipschitz with the constant declared in karst_relief_t.fn_lipschitz
 * (1/m). It must be a pure, thread-safe function of its arguments.
 */
typedef double (*karst_relief_fn)(const void *user, double u, double v);

/**
 * The relief of a warp node, |d| <= |amplitude| everywhere. Fill with
 * karst_relief_init() and set the fields of its kind.
 */
typedef struct karst_relief {
  karst_relief_kind_t kind;
  double amplitude; /**< A (m): d = A x (a relief in [-1, 1]); negative flips it */
  /* KARST_RELIEF_NOISE: fBm of value noise, octave o of wavelength λ/2^o and weight 2^-o */
  double wavelength; /**< λ of the first octave (m), default 1 */
  int octaves;       /**< 1..KARST_RELIEF_MAX_OCTAVES, default 3 */
  /* KARST_RELIEF_IMAGE: d = A (2 grey - 1), bilinear, repeated every tile metres */
  const karst_image_t *image; /**< copied into the tree */
  double tile;                /**< metres covered by the image's width, default 1 */
  /* KARST_RELIEF_FUNCTION: d = A fn(user, u, v) */
  karst_relief_fn fn;
  const void *user;    /**< must outlive the tree */
  double fn_lipschitz; /**< Lipschitz constant of fn (1/m) */
  /* KARST_RELIEF_FRACTURES: d = -A Σ_k w_k max_i b((n_k.p - c_ki) / width) / Σ_k w_k, b(x) =
   * (1 - x²)², fracture i of family k at c_ki = (i + U) spacing along n_k (U uniform) */
  int n_planes;                               /**< 1..KARST_RELIEF_MAX_PLANES */
  double normals[KARST_RELIEF_MAX_PLANES][3]; /**< normals of the families (normalised here) */
  double weights[KARST_RELIEF_MAX_PLANES];    /**< w_k >= 0, not all 0 */
  double spacing;                             /**< mean fracture spacing (m), default 2 */
  double width; /**< groove half-width (m), <= 4 spacing, default 0.3 */
} karst_relief_t;

/** Defaults of a relief of @p kind (amplitude 0.05 m; see karst_relief_t). */
void karst_relief_init(karst_relief_t *r, karst_relief_kind_t kind);

/** How a warp node takes the gradient of its child and where it displaces. */
typedef struct karst_warp_params {
  double epsilon;    /**< step of the finite-difference gradient of the child (m), default 0.2 */
  double grad_floor; /**< m in g = G / max(|G|, m), in (0, 1], default 0.5 */
  double band;       /**< > 0: displace only where |child| < band (m), faded out; INFINITY
                          (default): everywhere, as in the paper */
} karst_warp_params_t;

/** Fill @p p with the documented defaults. */
void karst_warp_params_init(karst_warp_params_t *p);

/**
 * Gradient-based warping (Paris et al. 2020, §4.3): the child c evaluated at
 * p + δ(p) with
 *     δ(p) = g(p) Σ_i α_i(p) d(γ_i(p)),  α_i = |g(p) . u_i|,
 * γ_i the projections on the yz, xz and xy planes and g the child's
 * normalised gradient (tri-planar; a KARST_RELIEF_FRACTURES relief is used as
 * δ = g d(p)). The gradient is the child's, by a tetrahedral finite
 * difference of step ε (exact for linear fields), normalised as
 * g = G / max(|G|, m) so that it is Lipschitz (constant 1/(ε m)) and fades
 * where the child has no direction (|G| < m, e.g. on a medial axis). With
 * δ being L_δ-Lipschitz (bound in warp.c), the warped field is
 * (1 + L_δ)-Lipschitz; it is divided by that factor (band = INFINITY), or, with
 * a finite band, δ is faded out by (1 - (c/band)²)² and the factor is applied
 * only within band + max|δ| of the surface (a piecewise-linear rescaling
 * that keeps the zero set and the distance bound, see warp.c), so that the
 * field far from the surface stays a tight distance bound.
 * @param child  any node
 * @param relief the relief (copied; an image is copied into the tree)
 * @param par    NULL for the defaults
 * @param rng    draws the seed of noise and fracture positions (may be NULL for
 *               image and function reliefs)
 * @return KARST_SUCCESS; KARST_EINVAL naming the bad field; KARST_ENOMEM.
 * Time: 6 child evaluations near the surface, 1 far from it.
 */
karst_error_t karst_sdf_warp(karst_ctx_t *ctx, karst_sdf_t *sdf, karst_int_t child,
                             const karst_relief_t *relief, const karst_warp_params_t *par,
                             karst_rng_t *rng, karst_int_t *node);

/**
 * The relief of warp node @p node at a point (tri-planar reliefs: d(u, v) at
 * (u, v) = (p[0], p[1]); fractures: d(p)). For tests and pictures.
 */
double karst_sdf_warp_relief(const karst_sdf_t *sdf, karst_int_t node, const double p[3]);
/** The factor 1 + L_δ of warp node @p node (1 when its amplitude is 0). */
double karst_sdf_warp_lipschitz(const karst_sdf_t *sdf, karst_int_t node);

/* ------------------------------------------------------------------------ */
/* Geometric details on skeleton-based surfaces (Zanni et al. 2012).          */
/* ------------------------------------------------------------------------ */

/**
 * A piece of the skeleton that drives the details: a segment whose
 * direction a->b is Zanni's Sk_i, a kernel radius and a type (the index of
 * its row in karst_details_params_t.type). Its weight at p is the field
 * contribution f_i = (1 - (dist(p, ab) / support)²)² (0 beyond support).
 */
typedef struct karst_skeleton_segment {
  double a[3], b[3];
  double support; /**< > 0 (m) */
  int type;       /**< 0..KARST_TUNNEL_TYPE_COUNT-1 */
} karst_skeleton_segment_t;

/** The half-width of the detail shell [iso-, iso+] is this times the largest amplitude. */
#define KARST_DETAILS_SHELL_FACTOR 8.0

typedef struct karst_details_params {
  karst_wall_details_t type[KARST_TUNNEL_TYPE_COUNT]; /**< per skeleton type (amplitude 0: none) */
  double band;       /**< the field is rescaled linearly within this distance of the surface (m);
                          at least shell + max|h| (0, the default: that minimum). Set it to
                          √3 voxel + 2 max|h| for unbiased vertices when polygonizing */
  double epsilon;    /**< finite-difference step of the child's gradient (m), default 0.25 */
  double grad_floor; /**< m in n = G / max(|G|, m), default 0.5 */
  double fade;       /**< s0: the frame fades and anisotropic details fade out where
                          |n x Wd| < s0 (Zanni §5, the singularity), default 0.5 */
  int impulses;      /**< Gabor impulses per noise cell (of side twice the largest kernel
                          radius), 1..16, default 8 */
} karst_details_params_t;

/** Defaults of karst_sdf_details (every type with amplitude 0). */
void karst_details_params_init(karst_details_params_t *p);

/**
 * Geometric details of Zanni et al. 2012 on any child field f_S (§3-4). For
 * p with f_S(p) in the shell [-R, R] (R = KARST_DETAILS_SHELL_FACTOR times the
 * largest amplitude), with n the child's normalised gradient (finite
 * difference, as the warp node), P_S = p - f_S n - f_S tan α τ the
 * projection on the surface along the gradient tilted by α towards τ, the
 * detail parameters (amplitude, frequency, bandwidth, orientation, tilt)
 * blended at P_S by the skeleton's field contributions f_i (§4), Wd = Σ f_i Sk_i
 * (Eq. 3-5), the frame b = n x Wd, t = b x n (§3) and the anisotropic surface
 * Gabor noise ν(P_S) in [-1, 1] along ω in (t, b) (§2),
 *     f(p) = f_S(p) - D ν(P_S) (1 - |f_S(p)|/R)^6     (§4, K(r) = (1 - r)^6),
 * and f = f_S elsewhere. Where |n x Wd| < fade (Wd ∥ ∇f, or Wd cancelling) the
 * anisotropic part fades out (Zanni §5). D is the blended amplitude raised so
 * that ν = ±1 moves the wall by exactly the amplitude. Positive details
 * enlarge the child's solid. The field is L-Lipschitz with L bounded in
 * details.c and is rescaled by 1/L within the band only (as the warp node's
 * band mode). With every amplitude 0 the node is its child, exactly.
 * @param child the surface to detail
 * @param seg   the skeleton (copied), @p n_seg >= 1
 * @param rng   draws the noise seed
 * @return KARST_SUCCESS; KARST_EINVAL naming the bad value; KARST_ENOMEM.
 * Time: 6 child evaluations and one noise evaluation in the shell, 1 elsewhere.
 */
karst_error_t karst_sdf_details(karst_ctx_t *ctx, karst_sdf_t *sdf, karst_int_t child,
                                const karst_details_params_t *par,
                                const karst_skeleton_segment_t *seg, karst_int_t n_seg,
                                karst_rng_t *rng, karst_int_t *node);

/** The Lipschitz factor L of a details node (1 when every amplitude is 0; 0 for other nodes). */
double karst_sdf_details_lipschitz(const karst_sdf_t *sdf, karst_int_t node);
/** Half-width R of a details node's shell [iso-, iso+] (m). */
double karst_sdf_details_shell(const karst_sdf_t *sdf, karst_int_t node);
/**
 * The normalised noise ν in [-1, 1] of a details node for the point p (at
 * its projection P_S on the surface, P_S = p on the surface), with the frame
 * and parameters there; and through @p frame (may be NULL) n, t, b. For tests
 * and pictures.
 */
double karst_sdf_details_noise(const karst_sdf_t *sdf, karst_int_t node, const double p[3],
                               double frame[3][3]);

/* ------------------------------------------------------------------------ */
/* Speleothems (beyond the papers: Paris et al. 2021, §8 future work).        */
/* ------------------------------------------------------------------------ */

/**
 * Round cone: the convex hull of the balls (a, ra) and (b, rb), which is the
 * union of the balls interpolated along ab; exact signed distance (hence
 * 1-Lipschitz). Needs ra, rb > 0 and |ra - rb| < |b - a|.
 */
karst_error_t karst_sdf_round_cone(karst_ctx_t *ctx, karst_sdf_t *sdf, const double a[3], double ra,
                                   const double b[3], double rb, int label, karst_int_t *node);

typedef enum { KARST_STALACTITE = 0, KARST_STALAGMITE = 1 } karst_speleothem_kind_t;

/** One speleothem: a round cone from its root (in the rock) to its tip. */
typedef struct karst_speleothem {
  karst_speleothem_kind_t kind;
  karst_int_t edge;            /**< the conduit edge it was drawn for */
  int type;                    /**< that edge's tunnel type */
  double root[3], root_radius; /**< the ball embedded in the ceiling (floor) */
  double tip[3], tip_radius;   /**< the ball at the free end */
  double ceiling, floor;       /**< z of the conduit's ceiling and floor above and below it */
} karst_speleothem_t;

/**
 * Place speleothems in the conduits of field @p conduits (negative in the
 * voids) of network @p net, by the rules of @p g per tunnel type: on each
 * edge with density ρ > 0, Poisson(ρ L w) candidates (L the length, w the
 * section's width), uniform over the middle 80 % of the length and 70 % of
 * the width, each drawn from the edge's own stream of (seed, realisation). A
 * vertical ray through the candidate finds the ceiling and floor (sphere
 * tracing on the 1-Lipschitz field); a stalactite of length drawn in
 * [min_length, max_length] hangs from the ceiling, shortened to leave
 * clearance above the floor; where floor to ceiling is less than
 * pair_height a stalagmite grows under it, leaving clearance between the
 * tips. A candidate is dropped when the ceiling and floor are too close,
 * when a speleothem's body is not certified inside the void (its balls
 * along the axis, by the field's bound), when its root is not in rock
 * (vertically up to twice its radius beyond its centre, and at 8 points
 * around it), or when it comes closer than twice its root radius to one
 * placed before. The root ball's centre is sunk @p embed metres (the wall
 * details' largest amplitude, so that no detail opens a gap) plus its
 * radius into the rock (so that it holds on ceilings sloping up to 45°). The list
 * (allocated, caller frees; NULL when empty) is in edge order.
 * Time: O(candidates x ray steps x field cost).
 */
karst_error_t karst_speleothems_place(karst_ctx_t *ctx, const karst_sdf_t *sdf,
                                      karst_int_t conduits, const karst_network_t *net,
                                      const karst_geometry_t *g, double default_radius,
                                      double embed, uint64_t seed, uint64_t realisation,
                                      karst_speleothem_t **out, karst_int_t *n);

/**
 * The union of speleothems as round cones labelled
 * KARST_SDF_LABEL(type, KARST_SDF_FEATURE_SPELEOTHEM), with a dripstone
 * relief of @p relief metres (a warp node in band mode, noise of wavelength
 * 0.3 m) when > 0. @p rng draws the relief's seed.
 */
karst_error_t karst_sdf_speleothems(karst_ctx_t *ctx, karst_sdf_t *sdf, const karst_speleothem_t *s,
                                    karst_int_t n, double relief, karst_rng_t *rng,
                                    karst_int_t *node);

/** Make @p node the root evaluated by karst_sdf_eval(). */
karst_error_t karst_sdf_set_root(karst_ctx_t *ctx, karst_sdf_t *sdf, karst_int_t node);
/** The current root (-1 when none). */
karst_int_t karst_sdf_root(const karst_sdf_t *sdf);

/**
 * Field of the root at @p p; @p label (may be NULL) receives the label of the
 * primitive that decided the value (the nearest primitive in a union).
 * Thread-safe (the tree is read only). Time: O(log n) for a union of n
 * well-separated primitives, O(n) worst case.
 */
double karst_sdf_eval(const karst_sdf_t *sdf, const double p[3], int *label);
/** Field of any node; @p touched (may be NULL) is increased by the hierarchy nodes visited. */
double karst_sdf_eval_node(const karst_sdf_t *sdf, karst_int_t node, const double p[3], int *label,
                           karst_int_t *touched);
/** Bounding box {lo, hi} of a node's solid (infinite for the terrain). */
void karst_sdf_node_box(const karst_sdf_t *sdf, karst_int_t node, double box[6]);

typedef struct karst_sdf_stats {
  karst_int_t n_nodes; /**< nodes in the tree */
  karst_int_t by_kind[KARST_SDF_KIND_COUNT];
  karst_int_t n_bvh_nodes; /**< hierarchy nodes over all unions */
  size_t memory_bytes;     /**< bytes held by the tree */
} karst_sdf_stats_t;
void karst_sdf_stats(const karst_sdf_t *sdf, karst_sdf_stats_t *st);

/* ------------------------------------------------------------------------ */
/* From a network to a tree (Paris et al. 2021, §6.2).                       */
/* ------------------------------------------------------------------------ */

typedef struct karst_implicit_params {
  double default_radius;   /**< radius (m) of edges without a "radius" attribute, default 1 */
  double mitre_max_angle;  /**< joints of two edges turning by at most this (degrees) get mitred
                                sweeps; sharper ones a union of Poisson spheres. Default 60 */
  int bend_spheres;        /**< sharp bends: 0 (default) revolve the two sections about the bend
                                axis (two exact primitives); 1 a union of Poisson spheres selected
                                by distance to interpolated sections (paper §6.2, Fig. 14) */
  double sphere_radius;    /**< R of the Poisson spheres (m), default 0.2 (paper §6.2) */
  double sphere_rel;       /**< ...but at least this fraction of the conduit radius, default 0.25,
                                which bounds the count per bend to about a thousand */
  double chamber_height;   /**< vertical semi-axis of chambers as a fraction of the radius, default
                              0.6 */
  double noise_amplitude;  /**< solid sparse-Gabor wall noise amplitude A (m), default 0 (off) */
  double noise_wavelength; /**< wavelength of that noise (m), default 2 */
  uint64_t seed;           /**< seed of the Poisson spheres and the noise, default 1 */
  uint64_t realisation;    /**< with seed, the streams of details and speleothems
                                (karst_rng_derive(seed, realisation, stage)), default 0 */
  const karst_geometry_t *geometry; /**< blending, wall details, speleothems, fracture relief
                                         (NULL: karst_geometry_init's defaults) */
  int details;     /**< 1 (default): the geometry's wall details; 0: smooth walls */
  int speleothems; /**< 1 (default): the geometry's speleothems; 0: none */
  double voxel;    /**< the polygonization's voxel (m) when known (0: not), so that the
                        detail fields stay linear over a voxel's diagonal */
  const karst_fracture_t *fractures; /**< fracture families of the grooves of
                                          geometry.fracture_relief (may be NULL) */
  int n_fractures;
} karst_implicit_params_t;

/** Fill @p par with the documented defaults. */
void karst_implicit_params_init(karst_implicit_params_t *par);

typedef struct karst_implicit_stats {
  karst_int_t n_sweeps, n_mitred_ends, n_ellipsoids, n_joint_balls, n_bends, n_spheres, n_revolves;
  karst_int_t n_skipped_edges; /**< zero-length edges */
  karst_int_t n_morphs;        /**< sweeps whose section or radius changes along the edge */
  karst_int_t n_blends;        /**< junctions combined by a smooth union */
  karst_int_t n_continuations; /**< edge pairs continuing each other across a junction */
  karst_int_t n_stalactites, n_stalagmites;
  double details_lipschitz; /**< L of the details node (0: no details) */
} karst_implicit_stats_t;

/**
 * Build the construction tree of a network's conduits into @p sdf and set its
 * root (Paris et al. 2021, §6.2, with the construction tree of issue 15):
 * one sweep per edge (section of its "tunnel_type", scaled by its "radius"),
 * whose section and area interpolate along the edge between the values at
 * its ends (at a node joining two edges, and across a junction between two
 * edges continuing each other, the mean of both); mitred at gentle joints of
 * two edges; at sharp bends the node's section revolved about the bend axis
 * (default) or a union of Poisson spheres (par->bend_spheres); ellipsoids for
 * chambers; a ball at junctions, smoothly united (blend) with the conduits
 * meeting there; the optional solid noise and fracture grooves; Zanni et al.
 * 2012 wall details; speleothems subtracted; with @p terrain non-NULL the
 * root is terrain minus conduits. @p stats may be NULL.
 * Time: O(E log E) plus the bends' spheres, the new section mixtures'
 * integration and the speleothems' ray casting.
 */
karst_error_t karst_implicit_build(karst_ctx_t *ctx, const karst_network_t *net,
                                   const karst_implicit_params_t *par,
                                   const karst_terrain_t *terrain, karst_sdf_t *sdf,
                                   karst_implicit_stats_t *stats);

#ifdef __cplusplus
}
#endif
#endif /* KARST_IMPLICIT_H */
