/* Private pieces shared by the files of src/implicit/: the node layout of the
 * construction tree, the bounding-volume hierarchy and the noise. */
#ifndef KARST_IMPLICIT_INTERNAL_H
#define KARST_IMPLICIT_INTERNAL_H

#include "karst/implicit.h"

/* Bounding boxes are padded by this absolute margin (m) plus this fraction of
 * the largest coordinate, so that a solid stays strictly inside its box after
 * rounding (the field is clamped from below by the box distance). */
#define KARST_I_BOX_PAD_ABS 1e-6
#define KARST_I_BOX_PAD_REL 1e-9

/* A sweep is "vertical" (its up axis falls back to world y) when |u . z|
 * exceeds this cosine (about 2.6 degrees from vertical). */
#define KARST_I_SWEEP_VERTICAL_COS 0.999

typedef struct karst_i_sweep {
  double a[3], u[3], side[3], up[3];
  double len;    /* |b - a| */
  double radius; /* scale of the section */
  double rho;    /* radius * max |control point|: the section lies in this disc */
  int section;   /* index into the tree's section table */
  int morph;     /* 0: the section; k > 0: the morphing section morphs[k - 1] (morph.c) */
  int mitre[2];  /* end a, end b */
  double n[2][3];
} karst_i_sweep_t;

typedef struct karst_i_revolve {
  double o[3], axis[3];
  double sx[2], sz[2]; /* section coordinates of the in-plane normal x and of the axis */
  double n[2][3];
  double radius, rho;
  int section;
  int morph;     /* 0: the section; k > 0: the mixture morphs[k - 1].wa (morph.c) */
  double offset; /* the cutting planes are moved out by this much (m) */
} karst_i_revolve_t;

/* Pieces of a conduit that meet at a joint (sweeps' caps, revolved halves)
 * overlap by this much (m), so that no point inside lies on both cutting
 * planes with field 0 (which a grid point there would read as outside). */
#define KARST_I_JOINT_OVERLAP 1e-4

/* Points of the smoothstep parameter at which a morphing sweep's scale is tabulated. */
#define KARST_I_MORPH_TAB 8

/* A morphing cross-section (morph.c): the unit fields of n sections mixed
 * with weights wa at one end and wb at the other, scaled by rho(t) so that the
 * area is interpolated; k is the Lipschitz factor the sweep is divided by. */
typedef struct karst_i_morph {
  int n;
  int sec[KARST_SECTION_MIX_MAX]; /* the tree's section table */
  double wa[KARST_SECTION_MIX_MAX], wb[KARST_SECTION_MIX_MAX];
  double len;                        /* sweep length (m) */
  double rho[KARST_I_MORPH_TAB + 1]; /* scale (m) at t = j / KARST_I_MORPH_TAB */
  double k;
} karst_i_morph_t;

/* A cached area of a unit mixture (morph.c). */
typedef struct karst_i_mix_area {
  int n;
  int sec[KARST_SECTION_MIX_MAX];
  double w[KARST_SECTION_MIX_MAX];
  double area;
} karst_i_mix_area_t;

typedef struct karst_i_noise {
  karst_int_t child;
  double amplitude;  /* A (m) */
  double wavelength; /* λ (m) */
  double kradius;    /* kernel window radius (m) */
  double lipschitz;  /* Ln of the normalised noise, 1/m */
  uint64_t seed;
} karst_i_noise_t;

/* A warp node's relief and constants (warp.c). */
typedef struct karst_i_warp {
  karst_int_t child;
  karst_relief_kind_t kind;
  double amp;         /* A, signed */
  double eps, gfloor; /* finite-difference step, gradient floor m */
  double band;        /* INFINITY: displace everywhere */
  double dmax;        /* largest |δ| */
  double lip;         /* 1 + L_δ: Lipschitz constant of the warped field */
  double rc;          /* band mode: the rescaling is linear (slope 1/lip) on |f| < rc */
  double rlip;        /* Lipschitz constant of the relief d itself (m/m) */
  /* noise */
  double wavelength;
  int octaves;
  uint64_t seed;
  /* image */
  int image; /* index into the tree's images */
  double tile;
  /* function */
  karst_relief_fn fn;
  const void *user;
  /* fractures */
  int n_planes;
  double normal[KARST_RELIEF_MAX_PLANES][3], weight[KARST_RELIEF_MAX_PLANES];
  double spacing, width;
} karst_i_warp_t;

/* An image held by the tree (warp reliefs), with its bilinear Lipschitz
 * constant in grey levels per pixel (tiled). */
typedef struct karst_i_image {
  int w, h;
  float *v;
  double lip;
} karst_i_image_t;

/* A segment of a details node's skeleton. */
typedef struct karst_i_dseg {
  double a[3], u[3], len, support;
  int type;
} karst_i_dseg_t;

/* Number of blended detail parameters (details.c). */
#define KARST_I_DETAIL_PARAMS 8

/* A details node (details.c): per-type parameters (amplitude raised to D,
 * frequency, kernel radius, orientation (cos, sin), anisotropy, tilt
 * tan α (cos θ, sin θ)), the background row that blending leans on away from
 * the skeleton, the constants of the bound and the skeleton's grid. */
typedef struct karst_i_details {
  karst_int_t child;
  double param[KARST_TUNNEL_TYPE_COUNT][KARST_I_DETAIL_PARAMS];
  double bg[KARST_I_DETAIL_PARAMS];
  double shell, rc, hmax, lip;
  double eps, gfloor, fade;
  double rk_max;
  int impulses;
  uint64_t seed;
  karst_i_dseg_t *seg;
  karst_int_t n_seg;
  double g0[3], gcell;
  karst_int_t gn[3];
  karst_int_t *gstart, *gitem; /* cell c holds gitem[gstart[c] .. gstart[c + 1]) */
  int overlap;                 /* most segments listed in one cell */
  int raw;                     /* 1: f_S - h unscaled (a KARST_SDF_RESCALE node above scales it) */
} karst_i_details_t;

typedef struct karst_i_node {
  karst_sdf_kind_t kind;
  int label;
  int finite;    /* box is finite */
  double box[6]; /* lo, hi of the solid (padded) */
  union {
    struct {
      double c[3], r;
    } sphere;
    struct {
      double c[3], axes[3][3], inv[3], rmin;
    } ell;
    karst_i_sweep_t sweep;
    struct {
      double lo[3], hi[3];
    } box;
    struct {
      int index;       /* into the tree's terrain table */
      double inv_norm; /* 1 / sqrt(1 + λ²) */
    } terrain;
    struct {
      karst_int_t first, n;         /* finite children kids[first .. first+n), in hierarchy order */
      karst_int_t inf_first, n_inf; /* unbounded children */
      karst_int_t bvh_root;         /* -1 without finite children */
    } uni;
    struct {
      karst_int_t a, b;
      double k;
    } bin;
    karst_i_noise_t noise;
    karst_i_revolve_t rev;
    struct {
      double u[3], d; /* u.p - d */
    } plane;
    struct {
      karst_int_t first, n; /* children kids[first .. first+n), in fold order */
      double R;
    } sint;
    struct {
      karst_int_t first; /* 3 n doubles in the tree's coordinate pool */
      int n, dim;        /* points; 0 point, 1 segment, 2 polygon */
      double radius;
      double o[3], e1[3], e2[3], nrm[3]; /* polygon frame (dim 2) */
    } thick;
    struct {
      karst_sdf_field_fn fn;
      const void *arg;
    } ext;
    struct {
      karst_int_t index; /* into the tree's warps (or details) */
    } warp;
    struct {
      karst_int_t child;
      double lip, rc; /* slope 1/lip on |f| <= rc, 1 beyond (details.c) */
    } rescale;
    struct {
      double a[3], u[3], len; /* axis a -> b */
      double ra, rb, sn, cs;  /* radii; sin and cos of the side's slope */
    } cone;
  } u;
} karst_i_node_t;

/* One node of a bounding-volume hierarchy: a leaf holds kids[a .. a+n),
 * an inner node (n == 0) has children a and b. */
typedef struct karst_i_bvh {
  double box[6];
  karst_int_t a, b;
  int n;
} karst_i_bvh_t;

struct karst_sdf {
  karst_i_node_t *nodes;
  karst_int_t n_nodes, cap_nodes;
  karst_int_t *kids;
  karst_int_t n_kids, cap_kids;
  karst_i_bvh_t *bvh;
  karst_int_t n_bvh, cap_bvh;
  karst_section_t *sections;
  int n_sections, cap_sections;
  double *coords; /* thick primitives' points */
  karst_int_t n_coords, cap_coords;
  karst_terrain_t *terrains; /* owned copies (z arrays owned) */
  int n_terrains, cap_terrains;
  karst_i_warp_t *warps;
  karst_int_t n_warps, cap_warps;
  karst_i_image_t *images; /* owned copies (pixels owned) */
  karst_int_t n_images, cap_images;
  karst_i_morph_t *morphs;
  karst_int_t n_morphs, cap_morphs;
  karst_i_mix_area_t *mix_areas; /* areas of unit mixtures already computed */
  karst_int_t n_mix_areas, cap_mix_areas;
  karst_i_details_t *details; /* owned skeletons and grids */
  karst_int_t n_details, cap_details;
  karst_int_t root;
};

/* Exact signed distance to an axis-aligned box {lo, hi}. */
double karst_i_sdbox(const double box[6], const double p[3]);

/* Normalised sparse Gabor noise in [-1, 1] (noise.c) and its Lipschitz bound. */
double karst_i_noise_eval(const karst_i_noise_t *nz, const double p[3]);
double karst_i_noise_lipschitz(double kradius, double wavelength);

/* Field of node @p id at @p p. Contract: when the true value is < ub the
 * exact value is returned (with its label); otherwise some value >= ub. */
double karst_i_sdf_eval(const karst_sdf_t *t, karst_int_t id, const double p[3], double ub,
                        int *label, karst_int_t *touched);

/* Frame (side, up) of a sweep with unit axis u and up hint (world z when NULL):
 * up is the hint made orthogonal to u (world y, then x, for vertical axes),
 * side = up x u. Returns -1 when no frame can be made. */
int karst_i_sweep_frame(const double u[3], const double up[3], double side[3], double upv[3]);

/* A new node of @p kind (label KARST_SDF_NO_LABEL, unbounded); *nd is valid
 * until the next node is made. */
karst_error_t karst_i_sdf_new_node(karst_ctx_t *ctx, karst_sdf_t *t, karst_sdf_kind_t kind,
                                   karst_i_node_t **nd, karst_int_t *id);
/* Grow a box by the rounding pad (KARST_I_BOX_PAD_*). */
void karst_i_pad_box(double box[6]);
/* Grow an array to hold @p need items; 0 or -1 (out of memory). */
int karst_i_grow(void **p, karst_int_t *cap, karst_int_t need, size_t size);

/* Fields of the blocks' nodes (smooth.c); same contract as karst_i_sdf_eval. */
double karst_i_eval_smooth_intersection(const karst_sdf_t *t, const karst_i_node_t *nd,
                                        const double p[3], double ub, int *label,
                                        karst_int_t *touched);
double karst_i_eval_thick(const karst_sdf_t *t, const karst_i_node_t *nd, const double p[3]);
/* Gradient of node @p child at @p p, where its (exact) value is @p f0, by the
 * tetrahedral finite difference of step @p eps (warp.c): G = (1/4ε) Σ_k v_k
 * f(p + ε v_k) over the vertices v_k of the cube (±1, ±1, ±1) with an even
 * number of minus signs. Exact for linear fields; for a 1-Lipschitz f, G is
 * (1/ε)-Lipschitz in p. */
void karst_i_fd_gradient(const karst_sdf_t *t, karst_int_t child, const double p[3], double f0,
                         double eps, double G[3], karst_int_t *touched);

/* Sweep and revolve primitives from a hull of in-plane points @p cp (unit,
 * scaled by @p radius) and a section index or a morph (sdf.c). */
karst_error_t karst_i_sweep_create(karst_ctx_t *ctx, karst_sdf_t *t, const double a[3],
                                   const double b[3], const double (*cp)[2], int ncp, double radius,
                                   int section, int morph, const double up[3],
                                   const karst_sweep_end_t ends[2], int label, karst_int_t *node);
karst_error_t karst_i_revolve_create(karst_ctx_t *ctx, karst_sdf_t *t, const double o[3],
                                     const double axis[3], const double side[3], const double up[3],
                                     const double (*cp)[2], int ncp, double radius, int section,
                                     int morph, const double n[2][3], double offset, int label,
                                     karst_int_t *node);
/* karst_sdf_revolve and karst_sdf_revolve_mix with the planes moved out by
 * @p offset (m) (sdf.c, morph.c). */
karst_error_t karst_i_revolve_offset(karst_ctx_t *ctx, karst_sdf_t *t, const double o[3],
                                     const double axis[3], const double side[3], const double up[3],
                                     const karst_section_t *section, double radius,
                                     const double n[2][3], double offset, int label,
                                     karst_int_t *node);
karst_error_t karst_i_revolve_mix_offset(karst_ctx_t *ctx, karst_sdf_t *t, const double o[3],
                                         const double axis[3], const double side[3],
                                         const double up[3], const karst_section_mix_t *m,
                                         double area, const double n[2][3], double offset,
                                         int label, karst_int_t *node);
/* Planning of the morphing sweeps' areas, so that they are integrated on several threads
 * (morph.c): karst_i_morph_plan adds the sections of a morphing sweep from @p ma to @p mb to the
 * tree exactly as karst_sdf_sweep_morph will, and a cache entry, its area not yet known, for each
 * unit mixture it will integrate that is not cached; karst_i_morph_integrate then integrates the
 * entries from @p first on, on @p nthreads threads (each entry alone: the areas do not depend on
 * the thread count). karst_sdf_sweep_morph then finds them cached. */
karst_error_t karst_i_morph_plan(karst_ctx_t *ctx, karst_sdf_t *t, const karst_section_mix_t *ma,
                                 const karst_section_mix_t *mb);
void karst_i_morph_integrate(karst_sdf_t *t, karst_int_t first, int nthreads);
/* In-plane distance (m) of a morphing sweep at axial position l and section
 * coordinates (x, y) (morph.c). */
double karst_i_morph_sweep_w(const karst_sdf_t *t, const karst_i_morph_t *m, double l, double x,
                             double y);
/* Unit mixture distance Σ w_k d_k(q) of a morph's sections with weights @p w. */
double karst_i_morph_mix_w(const karst_sdf_t *t, const karst_i_morph_t *m, const double *w,
                           const double q[2]);

/* Exact distance to a round cone (speleothem.c). */
double karst_i_round_cone_eval(const karst_i_node_t *nd, const double p[3]);

/* Field of a details node (details.c); same contract as karst_i_sdf_eval. */
double karst_i_details_eval(const karst_sdf_t *t, const karst_i_node_t *nd, const double p[3],
                            double ub, int *label, karst_int_t *touched);
/* karst_sdf_details, with @p raw = 1 a node that returns f_S - h unscaled:
 * L-Lipschitz (karst_sdf_details_lipschitz), locally 1-Lipschitz beyond
 * karst_i_details_band of the surface. Min and max with 1-Lipschitz fields
 * keep both properties, so that a KARST_SDF_RESCALE node of (L, band) above
 * them makes the result 1-Lipschitz (details.c). */
karst_error_t karst_i_details_create(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t child,
                                     const karst_details_params_t *par,
                                     const karst_skeleton_segment_t *seg, karst_int_t n_seg,
                                     karst_rng_t *rng, int raw, karst_int_t *node);
double karst_i_details_band(const karst_sdf_t *t, karst_int_t node);
/* The piecewise-linear rescaling (slope 1/lip within rc of 0, 1 beyond) of a
 * child, and its field (details.c). */
karst_error_t karst_i_rescale(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t child, double lip,
                              double rc, karst_int_t *node);
double karst_i_rescale_eval(const karst_sdf_t *t, const karst_i_node_t *nd, const double p[3],
                            double ub, int *label, karst_int_t *touched);
/* Release what a details node holds. */
void karst_i_details_free(karst_i_details_t *d);

/* 3-vector dot and cross products of the files of src/implicit/. */
static inline double karst_i_dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void karst_i_cross3(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

/* SplitMix64's finaliser, and a pure function of (seed, a, b, c) uniform in
 * [0, 1): the deterministic draws of procedural noise (warp.c). */
uint64_t karst_i_mix64(uint64_t z);
double karst_i_hash_unit(uint64_t seed, uint64_t a, int64_t b, int64_t c);

/* Field of a warp node (warp.c); same contract as karst_i_sdf_eval. */
double karst_i_warp_eval(const karst_sdf_t *t, const karst_i_node_t *nd, const double p[3],
                         double ub, int *label, karst_int_t *touched);

/* Empty a tree (keeps its storage): no half-built tree survives a failure. */
void karst_i_sdf_clear(karst_sdf_t *t);

/* Add a section to the tree's table (deduplicated by content); index in *out. */
karst_error_t karst_i_sdf_add_section(karst_ctx_t *ctx, karst_sdf_t *t, const karst_section_t *s,
                                      int *out);

#endif
