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
  int mitre[2];  /* end a, end b */
  double n[2][3];
} karst_i_sweep_t;

typedef struct karst_i_revolve {
  double o[3], axis[3];
  double sx[2], sz[2]; /* section coordinates of the in-plane normal x and of the axis */
  double n[2][3];
  double radius, rho;
  int section;
} karst_i_revolve_t;

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
      karst_int_t index; /* into the tree's warps */
    } warp;
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
/* Gradient of node @p child at @p p by the tetrahedral finite difference of
 * step @p eps (warp.c): G = (1/4ε) Σ_k v_k f(p + ε v_k) over the vertices
 * v_k of the cube (±1, ±1, ±1) with an even number of minus signs. Exact for
 * linear fields; for a 1-Lipschitz f, G is (1/ε)-Lipschitz in p. */
void karst_i_fd_gradient(const karst_sdf_t *t, karst_int_t child, const double p[3], double eps,
                         double G[3], karst_int_t *touched);

/* Field of a warp node (warp.c); same contract as karst_i_sdf_eval. */
double karst_i_warp_eval(const karst_sdf_t *t, const karst_i_node_t *nd, const double p[3],
                         double ub, int *label, karst_int_t *touched);

/* Empty a tree (keeps its storage): no half-built tree survives a failure. */
void karst_i_sdf_clear(karst_sdf_t *t);

/* Add a section to the tree's table (deduplicated by content); index in *out. */
karst_error_t karst_i_sdf_add_section(karst_ctx_t *ctx, karst_sdf_t *t, const karst_section_t *s,
                                      int *out);

#endif
