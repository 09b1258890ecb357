/* Geometric details on skeleton-based implicit surfaces (Zanni et al. 2012):
 * frames from the weighted skeleton direction and the gradient (§3), the
 * anisotropic surface Gabor noise (§2, after Lagae et al. 2009), the
 * deformation of the field inside [iso-, iso+] by projection onto the
 * surface with K(r) = (1 - r)^6 (§4), detail parameters blended between
 * primitives by their field contributions (§4), and a proven Lipschitz bound.
 *
 * Notation. f_S is the child (1-Lipschitz), R the shell half-width; on
 * |f_S| < R:
 *   n   = G / max(|G|, m), G the tetrahedral finite difference of step ε:
 *         |n| <= 1, L_n = 1/(ε m) (proof in warp.c);
 *   x0  = p - f_S n:                    L_x0 <= 2 + R L_n;
 *   f_i = (1 - (d_i / R_i)²)², d_i the distance to segment i (support R_i):
 *         |∇f_i| = (4 d_i / R_i²) sqrt(f_i) <= (4 / R_i) sqrt(f_i);
 *   blended parameter θ = (Σ f_i θ_i + ε_w θ_bg) / (S + ε_w), S = Σ f_i:
 *         ∇θ = Σ ∇f_i (θ_i - θ) / (S + ε_w), and with at most M segments active
 *         (Cauchy-Schwarz) Σ |∇f_i| <= (4/R_min) sqrt(M S), so
 *         |∇θ| <= Δθ (4/R_min) sqrt(M) sqrt(S) / (S + ε_w) <= Δθ L_w,
 *         L_w = 2 sqrt(M / ε_w) / R_min, Δθ the parameter's range;
 *   Ŵd  = Σ f_i Sk_i / (S + ε_w): |Ŵd| < 1 and (the same way) L_Wd <= 2 L_w;
 *   c   = n x Ŵd(x0): |c| <= 1, L_c <= L_n + 2 L_w L_x0;
 *   b   = c / max(|c|, s0) (projection onto a ball, scaled): L_b <= L_c / s0;
 *   t   = b x n: L_t <= L_b + L_n;  fade φ = min(1, |c|/s0): L_φ <= L_c / s0;
 *   τ   = T1 t + T2 b (T = tan α (cos θ, sin θ) blended, |T| <= T_m);
 *   P_S = x0 - f_S τ: L_PS <= L_x0 + T_m + R (L_T1 + L_T2 + T_m (L_t + L_b));
 *   ω_a = o1 t + o2 b (o = (cos ω, sin ω) blended): L_ω <= L_o1 + L_o2 + L_t + L_b;
 *   Ω_i = (1 - κ) (d_i - (d_i.n) n) + κ ω_a, d_i the impulse's unit direction:
 *         |Ω_i| <= 1, L_Ω <= 2 L_κ + 2 L_n + L_ω.
 * The noise ν_s = Σ w_i W_i cos(2π F Ω_i.(x - x_i)) / (ε_ν + Σ W_i) with
 * W_i = (1 - |x - x_i|² / r_k²)², |w_i| <= 1: |ν_s| <= 1, and since
 * |dW/dr| <= (4 / r_k) sqrt(W), |∂W/∂r_k| <= (4 / r_k) sqrt(W), at most N
 * kernels reach a point, and |x - x_i| < r_k <= r_max where W_i > 0,
 *   L_ν <= (2π F_max + Q) L_PS + 2π F_max r_max L_Ω + 2π r_max L_F + Q L_rk,
 *   Q = 4 sqrt(N / ε_ν) / r_min (from 2 Σ|∂W| / (ε_ν + ΣW) <= (8/r) sqrt(N S)/(ε_ν + S)),
 * for ν_s, and ν = sat(GAIN ν_s) has |ν| < 1 and GAIN times that constant.
 * With γ = 1 - κ + κ φ in [0, 1] (L_γ <= L_κ + L_φ) and d = D γ ν (|d| <= H):
 *   L_d <= L_D + H L_γ + H L_ν,   h = d (1 - |f_S|/R)^6:  L_h <= L_d + 6 H / R,
 * and f = f_S - h is L = 1 + L_h Lipschitz. Outside the shell f = f_S; since
 * |f - f_S| <= H, |f| > rc = R + H implies |f_S| > R, where f is locally
 * 1-Lipschitz: the piecewise-linear rescaling of warp.c (slope 1/L on
 * |f| <= rc) makes f 1-Lipschitz with the same zero set. The bound is
 * conservative (the tests measure by how much). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "implicit/implicit_internal.h"

/* Weight of the background parameters (amplitude 0) against the skeleton's. */
#define EPS_W 0.25
/* ε_ν of the noise's normalisation Σ w W cos / (ε_ν + Σ W). */
#define EPS_NU 0.5
/* Largest tilt accepted (degrees): tan 60° bounds the projection's lean. */
#define MAX_TILT 60.0
/* The normalised sum of kernels is a weighted mean of values in [-1, 1], whose
 * typical size is about a sixth of its bound: ν = sat(GAIN ν_sum) with
 * sat(x) = x / sqrt(1 + x²) (slope <= 1, |sat| < 1) brings it to about 0.4. */
#define GAIN 3.0
/* Most cells of a skeleton grid; beyond it the cells are made larger. */
#define MAX_GRID_CELLS (1 << 22)

enum { P_AMP, P_F, P_RK, P_O1, P_O2, P_KAP, P_T1, P_T2 };

/** Defaults of karst_sdf_details (see implicit.h). O(1). */
void karst_details_params_init(karst_details_params_t *p) {
  memset(p, 0, sizeof *p);
  for (int k = 0; k < KARST_TUNNEL_TYPE_COUNT; k++) {
    p->type[k].wavelength = 0.5;
    p->type[k].bandwidth = 2.0;
  }
  p->band = 0;
  p->epsilon = 0.25;
  p->grad_floor = 0.5;
  p->fade = 0.5;
  p->impulses = 8;
}

void karst_i_details_free(karst_i_details_t *d) {
  free(d->seg);
  free(d->gstart);
  free(d->gitem);
  memset(d, 0, sizeof *d);
}

/* ---------------------------------------------------------------------- */
/* The skeleton: weights, blended parameters and Wd at a point.            */
/* ---------------------------------------------------------------------- */

typedef struct {
  double S;                            /* Σ f_i */
  double theta[KARST_I_DETAIL_PARAMS]; /* blended parameters */
  double wd[3];                        /* Ŵd = Σ f_i Sk_i / (S + ε_w) */
} blend_t;

static void gather(const karst_i_details_t *d, const double x[3], blend_t *b) {
  double sum[KARST_I_DETAIL_PARAMS] = {0}, wd[3] = {0, 0, 0}, S = 0;
  karst_int_t c[3];
  int inside = 1;
  for (int a = 0; a < 3; a++) {
    double q = floor((x[a] - d->g0[a]) / d->gcell);
    if (!(q >= 0 && q < (double)d->gn[a])) inside = 0;
    c[a] = inside ? (karst_int_t)q : 0;
  }
  if (inside) {
    karst_int_t cell = (c[2] * d->gn[1] + c[1]) * d->gn[0] + c[0];
    for (karst_int_t i = d->gstart[cell]; i < d->gstart[cell + 1]; i++) {
      const karst_i_dseg_t *s = &d->seg[d->gitem[i]];
      double v[3] = {x[0] - s->a[0], x[1] - s->a[1], x[2] - s->a[2]};
      double l = karst_i_dot3(v, s->u);
      l = l < 0 ? 0 : (l > s->len ? s->len : l);
      double e[3] = {v[0] - l * s->u[0], v[1] - l * s->u[1], v[2] - l * s->u[2]};
      double q = karst_i_dot3(e, e) / (s->support * s->support);
      if (q >= 1) continue;
      double f = (1 - q) * (1 - q);
      S += f;
      for (int k = 0; k < KARST_I_DETAIL_PARAMS; k++)
        sum[k] += f * d->param[s->type][k];
      for (int k = 0; k < 3; k++)
        wd[k] += f * s->u[k];
    }
  }
  double den = S + EPS_W;
  b->S = S;
  for (int k = 0; k < KARST_I_DETAIL_PARAMS; k++)
    b->theta[k] = (sum[k] + EPS_W * d->bg[k]) / den;
  for (int k = 0; k < 3; k++)
    b->wd[k] = wd[k] / den;
}

/* The frame (n, t, b) from n and Ŵd, and the fade φ. */
static void frame(const karst_i_details_t *d, const double n[3], const double wd[3], double t[3],
                  double bb[3], double *phi) {
  double c[3];
  karst_i_cross3(n, wd, c);
  double cl = sqrt(karst_i_dot3(c, c));
  double s = 1.0 / (cl > d->fade ? cl : d->fade);
  for (int k = 0; k < 3; k++)
    bb[k] = c[k] * s;
  karst_i_cross3(bb, n, t);
  *phi = cl >= d->fade ? 1 : cl / d->fade;
}

/* ---------------------------------------------------------------------- */
/* Anisotropic surface Gabor noise.                                        */
/* ---------------------------------------------------------------------- */

static double unit_of(uint64_t *h) {
  *h = karst_i_mix64(*h + 0x9E3779B97F4A7C15ULL);
  return (double)(*h >> 11) * 0x1p-53;
}

/* ν at x: impulses of the 8 cells (side 2 r_max) a ball of radius r_max
 * around x can reach, each with position, weight in [-1, 1] and direction
 * drawn from (seed, cell, index); kernel W(r/r_k) cos(2π F Ω.(x - x_i)). */
static double gabor(const karst_i_details_t *d, const double x[3], const double n[3],
                    const double wa[3], double kap, double F, double rk) {
  const double cs = 2 * d->rk_max, rk2 = rk * rk, w2pi = 2 * M_PI * F;
  int64_t c[3], o[3];
  for (int a = 0; a < 3; a++) {
    double q = x[a] / cs, fl = floor(q);
    c[a] = (int64_t)fl;
    o[a] = q - fl < 0.5 ? -1 : 1;
  }
  double num = 0, den = EPS_NU;
  for (int m = 0; m < 8; m++) {
    int64_t ci = c[0] + ((m & 1) ? o[0] : 0), cj = c[1] + ((m & 2) ? o[1] : 0),
            ck = c[2] + ((m & 4) ? o[2] : 0);
    uint64_t key = karst_i_mix64(d->seed ^ karst_i_mix64((uint64_t)ci * 0x9E3779B97F4A7C15ULL ^
                                                         (uint64_t)cj * 0xC2B2AE3D27D4EB4FULL ^
                                                         (uint64_t)ck * 0x165667B19E3779F9ULL));
    for (int j = 0; j < d->impulses; j++) {
      uint64_t h = key + (uint64_t)j * 0xD6E8FEB86659FD93ULL;
      double xi[3] = {(ci + unit_of(&h)) * cs, (cj + unit_of(&h)) * cs, (ck + unit_of(&h)) * cs};
      double v[3] = {x[0] - xi[0], x[1] - xi[1], x[2] - xi[2]};
      double r2 = karst_i_dot3(v, v);
      if (r2 >= rk2) {
        continue;
      }
      double w = 2 * unit_of(&h) - 1;
      double z = 2 * unit_of(&h) - 1, ph = 2 * M_PI * unit_of(&h), s = sqrt(1 - z * z);
      double di[3] = {s * cos(ph), s * sin(ph), z};
      double dn = karst_i_dot3(di, n), om[3];
      for (int k = 0; k < 3; k++)
        om[k] = (1 - kap) * (di[k] - dn * n[k]) + kap * wa[k];
      double W = (1 - r2 / rk2) * (1 - r2 / rk2);
      num += w * W * cos(w2pi * karst_i_dot3(om, v));
      den += W;
    }
  }
  double x0 = GAIN * num / den;
  return x0 / sqrt(1 + x0 * x0);
}

/* ---------------------------------------------------------------------- */
/* The node.                                                               */
/* ---------------------------------------------------------------------- */

static double squash(const karst_i_details_t *d, double x) {
  if (d->raw) return x; /* a KARST_SDF_RESCALE node above applies it */
  if (fabs(x) <= d->rc) return x / d->lip;
  double off = d->rc * (1 - 1 / d->lip);
  return x > 0 ? x - off : x + off;
}

static double unsquash(const karst_i_details_t *d, double y) {
  if (d->raw) return y;
  if (fabs(y) * d->lip <= d->rc) return y * d->lip;
  double off = d->rc * (1 - 1 / d->lip);
  return y > 0 ? y + off : y - off;
}

/* Gradient direction, projection and blended parameters at p (f = f_S(p)):
 * fills n, the projected point ps, the blend and the frame. */
typedef struct {
  double n[3], ps[3], t[3], b[3], phi, wa[3];
  blend_t bl;
} local_t;

static void local_frame(const karst_sdf_t *t, const karst_i_details_t *d, const double p[3],
                        double f, local_t *L, karst_int_t *touched) {
  double G[3];
  karst_i_fd_gradient(t, d->child, p, f, d->eps, G, touched);
  double gn = sqrt(karst_i_dot3(G, G)), s = 1.0 / (gn > d->gfloor ? gn : d->gfloor);
  for (int k = 0; k < 3; k++)
    L->n[k] = G[k] * s;
  double x0[3] = {p[0] - f * L->n[0], p[1] - f * L->n[1], p[2] - f * L->n[2]};
  gather(d, x0, &L->bl);
  frame(d, L->n, L->bl.wd, L->t, L->b, &L->phi);
  const double *th = L->bl.theta;
  for (int k = 0; k < 3; k++) {
    double tau = th[P_T1] * L->t[k] + th[P_T2] * L->b[k];
    L->ps[k] = x0[k] - f * tau;
    L->wa[k] = th[P_O1] * L->t[k] + th[P_O2] * L->b[k];
  }
}

double karst_i_details_eval(const karst_sdf_t *t, const karst_i_node_t *nd, const double p[3],
                            double ub, int *label, karst_int_t *touched) {
  const karst_i_details_t *d = &t->details[nd->u.warp.index];
  int lab = nd->label;
  if (d->hmax == 0) {
    double v = karst_i_sdf_eval(t, d->child, p, ub, &lab, touched);
    if (label) *label = lab;
    return v;
  }
  /* f >= f_S - H: one evaluation decides far points */
  double cub = isfinite(ub) ? unsquash(d, ub) + d->hmax : INFINITY;
  double f = karst_i_sdf_eval(t, d->child, p, cub, &lab, touched), v;
  if (f >= cub) {
    /* >= ub: valid under the contract (the max keeps it so through rounding) */
    v = fmax(squash(d, f - d->hmax), ub);
  } else if (fabs(f) >= d->shell) {
    v = squash(d, f);
  } else {
    local_t L;
    local_frame(t, d, p, f, &L, touched);
    const double *th = L.bl.theta;
    double nu = gabor(d, L.ps, L.n, L.wa, th[P_KAP], th[P_F], th[P_RK]);
    double g = 1 - th[P_KAP] + th[P_KAP] * L.phi;
    double r = 1 - fabs(f) / d->shell, r3 = r * r * r;
    v = squash(d, f - th[P_AMP] * g * nu * r3 * r3);
  }
  if (label) *label = lab;
  return v;
}

/* The bound of the file comment. @p ext: the parameters' ranges Δθ; the
 * other constants from @p d. */
static double details_lipschitz(const karst_i_details_t *d, const double range[], double r_min_seg,
                                double rk_min, double f_max, double t_max) {
  double Ln = 1.0 / (d->eps * d->gfloor), R = d->shell, H = d->hmax;
  double Lx0 = 2 + R * Ln;
  double Lw = 2 * sqrt(d->overlap / EPS_W) / r_min_seg;
  double Lth[KARST_I_DETAIL_PARAMS];
  for (int k = 0; k < KARST_I_DETAIL_PARAMS; k++)
    Lth[k] = range[k] * Lw * Lx0;
  double Lc = Ln + 2 * Lw * Lx0;
  double Lb = Lc / d->fade, Lt = Lb + Ln, Lphi = Lc / d->fade;
  double Ltau = Lth[P_T1] + Lth[P_T2] + t_max * (Lt + Lb);
  double Lps = Lx0 + t_max + R * Ltau;
  double Lom = Lth[P_O1] + Lth[P_O2] + Lt + Lb;
  double LOm = 2 * Lth[P_KAP] + 2 * Ln + Lom;
  double N = 8.0 * d->impulses, Q = 4 * sqrt(N / EPS_NU) / rk_min;
  double Lnu = GAIN * ((2 * M_PI * f_max + Q) * Lps + 2 * M_PI * f_max * d->rk_max * LOm +
                       2 * M_PI * d->rk_max * Lth[P_F] + Q * Lth[P_RK]);
  double Lg = Lth[P_KAP] + Lphi;
  double Ld = Lth[P_AMP] + H * Lg + H * Lnu;
  return 1 + Ld + 6 * H / R;
}

static karst_error_t check_type(karst_ctx_t *ctx, int k, const karst_wall_details_t *w) {
  const char *name = karst_tunnel_type_name((karst_tunnel_type_t)k);
  if (!(w->amplitude >= 0) || !isfinite(w->amplitude))
    return karst_set_error(ctx, KARST_EINVAL, "details of %s: amplitude %g must be >= 0 m", name,
                           w->amplitude);
  if (w->amplitude == 0) return KARST_SUCCESS;
  if (!(w->wavelength > 0) || !isfinite(w->wavelength))
    return karst_set_error(ctx, KARST_EINVAL, "details of %s: wavelength %g must be > 0 m", name,
                           w->wavelength);
  if (!(w->bandwidth > 0) || !isfinite(w->bandwidth))
    return karst_set_error(ctx, KARST_EINVAL, "details of %s: bandwidth %g must be > 0 per m", name,
                           w->bandwidth);
  if (!(w->orientation >= -90 && w->orientation <= 90))
    return karst_set_error(ctx, KARST_EINVAL,
                           "details of %s: orientation %g must be in [-90, 90] degrees", name,
                           w->orientation);
  if (!(w->anisotropy >= 0 && w->anisotropy <= 1))
    return karst_set_error(ctx, KARST_EINVAL, "details of %s: anisotropy %g must be in [0, 1]",
                           name, w->anisotropy);
  if (!(w->tilt >= 0 && w->tilt <= MAX_TILT))
    return karst_set_error(ctx, KARST_EINVAL, "details of %s: tilt %g must be in [0, %g] degrees",
                           name, w->tilt, MAX_TILT);
  if (!isfinite(w->tilt_direction))
    return karst_set_error(ctx, KARST_EINVAL, "details of %s: tilt_direction %g is not finite",
                           name, w->tilt_direction);
  return KARST_SUCCESS;
}

/* The skeleton's grid: cells of side gcell (the largest support, doubled
 * until at most MAX_GRID_CELLS cells), each listing every segment whose
 * support box meets it. */
static karst_error_t build_grid(karst_ctx_t *ctx, karst_i_details_t *d) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double smax = 0;
  for (karst_int_t i = 0; i < d->n_seg; i++) {
    const karst_i_dseg_t *s = &d->seg[i];
    smax = fmax(smax, s->support);
    for (int a = 0; a < 3; a++) {
      double e = s->a[a] + s->len * s->u[a];
      lo[a] = fmin(lo[a], fmin(s->a[a], e) - s->support);
      hi[a] = fmax(hi[a], fmax(s->a[a], e) + s->support);
    }
  }
  d->gcell = smax;
  double cells;
  for (;;) {
    cells = 1;
    for (int a = 0; a < 3; a++)
      cells *= floor((hi[a] - lo[a]) / d->gcell) + 1;
    if (cells <= MAX_GRID_CELLS) break;
    d->gcell *= 2;
  }
  for (int a = 0; a < 3; a++) {
    d->g0[a] = lo[a];
    d->gn[a] = (karst_int_t)floor((hi[a] - lo[a]) / d->gcell) + 1;
  }
  karst_int_t nc = d->gn[0] * d->gn[1] * d->gn[2];
  d->gstart = calloc((size_t)nc + 1, sizeof *d->gstart);
  if (!d->gstart) return karst_set_error(ctx, KARST_ENOMEM, "details: out of memory for the grid");
  for (int pass = 0; pass < 2; pass++) {
    for (karst_int_t i = 0; i < d->n_seg; i++) {
      const karst_i_dseg_t *s = &d->seg[i];
      karst_int_t c0[3], c1[3];
      for (int a = 0; a < 3; a++) {
        double e = s->a[a] + s->len * s->u[a];
        c0[a] = (karst_int_t)floor((fmin(s->a[a], e) - s->support - d->g0[a]) / d->gcell);
        c1[a] = (karst_int_t)floor((fmax(s->a[a], e) + s->support - d->g0[a]) / d->gcell);
        if (c0[a] < 0) c0[a] = 0;
        if (c1[a] >= d->gn[a]) c1[a] = d->gn[a] - 1;
      }
      for (karst_int_t z = c0[2]; z <= c1[2]; z++)
        for (karst_int_t y = c0[1]; y <= c1[1]; y++)
          for (karst_int_t x = c0[0]; x <= c1[0]; x++) {
            karst_int_t c = (z * d->gn[1] + y) * d->gn[0] + x;
            if (pass == 0)
              d->gstart[c + 1]++;
            else
              d->gitem[d->gstart[c]++] = i;
          }
    }
    if (pass == 0) {
      d->overlap = 0;
      for (karst_int_t c = 0; c < nc; c++) {
        if (d->gstart[c + 1] > d->overlap) d->overlap = (int)d->gstart[c + 1];
        d->gstart[c + 1] += d->gstart[c];
      }
      d->gitem = malloc((size_t)(d->gstart[nc] > 0 ? d->gstart[nc] : 1) * sizeof *d->gitem);
      if (!d->gitem)
        return karst_set_error(ctx, KARST_ENOMEM, "details: out of memory for the grid");
    } else {
      for (karst_int_t c = nc; c > 0; c--)
        d->gstart[c] = d->gstart[c - 1];
      d->gstart[0] = 0;
    }
  }
  return KARST_SUCCESS;
}

/**
 * Geometric details (Zanni et al. 2012); see implicit.h and the bound at the
 * top of this file.
 * Time complexity: O(segments x cells each covers) to build.
 */
karst_error_t karst_sdf_details(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t child,
                                const karst_details_params_t *par,
                                const karst_skeleton_segment_t *seg, karst_int_t n_seg,
                                karst_rng_t *rng, karst_int_t *node) {
  return karst_i_details_create(ctx, t, child, par, seg, n_seg, rng, 0, node);
}

karst_error_t karst_i_details_create(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t child,
                                     const karst_details_params_t *par,
                                     const karst_skeleton_segment_t *seg, karst_int_t n_seg,
                                     karst_rng_t *rng, int raw, karst_int_t *node) {
  karst_details_params_t defaults;
  if (!par) {
    karst_details_params_init(&defaults);
    par = &defaults;
  }
  if (!t || child < 0 || child >= t->n_nodes)
    return karst_set_error(ctx, KARST_EINVAL, "details: node %lld does not exist (tree has %lld)",
                           (long long)child, t ? (long long)t->n_nodes : 0LL);
  if (!seg || n_seg < 1)
    return karst_set_error(ctx, KARST_EINVAL, "details: no skeleton segment given");
  if (!rng) return karst_set_error(ctx, KARST_EINVAL, "details: no random generator given");
  if (!(par->epsilon > 0) || !isfinite(par->epsilon) || !(par->grad_floor > 0) ||
      !(par->grad_floor <= 1))
    return karst_set_error(ctx, KARST_EINVAL,
                           "details: gradient step %g must be > 0 m and grad_floor %g in (0, 1]",
                           par->epsilon, par->grad_floor);
  if (!(par->fade > 0 && par->fade <= 1))
    return karst_set_error(ctx, KARST_EINVAL, "details: fade %g must be in (0, 1]", par->fade);
  if (par->impulses < 1 || par->impulses > 16)
    return karst_set_error(ctx, KARST_EINVAL, "details: %d impulses per cell, expected 1..16",
                           par->impulses);
  if (!(par->band >= 0) || !isfinite(par->band))
    return karst_set_error(ctx, KARST_EINVAL, "details: band %g must be >= 0 m", par->band);
  karst_error_t err;
  double amax = 0;
  for (int k = 0; k < KARST_TUNNEL_TYPE_COUNT; k++) {
    if ((err = check_type(ctx, k, &par->type[k]))) return err;
    amax = fmax(amax, par->type[k].amplitude);
  }
  for (karst_int_t i = 0; i < n_seg; i++) {
    const karst_skeleton_segment_t *s = &seg[i];
    if (!isfinite(s->a[0] + s->a[1] + s->a[2] + s->b[0] + s->b[1] + s->b[2]) || !(s->support > 0) ||
        !isfinite(s->support) || s->type < 0 || s->type >= KARST_TUNNEL_TYPE_COUNT)
      return karst_set_error(ctx, KARST_EINVAL,
                             "details: skeleton segment %lld has support %g and type %d (support "
                             "> 0, type 0..%d, finite ends)",
                             (long long)i, s->support, s->type, KARST_TUNNEL_TYPE_COUNT - 1);
  }
  karst_i_details_t d;
  memset(&d, 0, sizeof d);
  d.child = child;
  d.raw = raw;
  d.eps = par->epsilon;
  d.gfloor = par->grad_floor;
  d.fade = par->fade;
  d.impulses = par->impulses;
  d.seed = karst_rng_u64(rng);
  d.shell = KARST_DETAILS_SHELL_FACTOR * amax;
  /* parameters: types with details, then the background (their mid-range) */
  double lo[KARST_I_DETAIL_PARAMS], hi[KARST_I_DETAIL_PARAMS];
  for (int k = 0; k < KARST_I_DETAIL_PARAMS; k++)
    lo[k] = INFINITY, hi[k] = -INFINITY;
  double rk_min = INFINITY, f_max = 0, t_max = 0;
  for (int k = 0; k < KARST_TUNNEL_TYPE_COUNT; k++) {
    const karst_wall_details_t *w = &par->type[k];
    if (w->amplitude == 0) continue;
    double *q = d.param[k], a = w->amplitude, r = 1 - a / d.shell;
    double om = w->orientation * M_PI / 180, ta = tan(w->tilt * M_PI / 180),
           th = w->tilt_direction * M_PI / 180;
    /* raised so that ν = ±1 moves the wall by a: f_S = D (1 - f_S/R)^6 at f_S = a */
    q[P_AMP] = a / (r * r * r * r * r * r);
    q[P_F] = 1 / w->wavelength;
    q[P_RK] = 1 / w->bandwidth;
    q[P_O1] = cos(om), q[P_O2] = sin(om);
    q[P_KAP] = w->anisotropy;
    q[P_T1] = ta * cos(th), q[P_T2] = ta * sin(th);
    for (int j = 0; j < KARST_I_DETAIL_PARAMS; j++)
      lo[j] = fmin(lo[j], q[j]), hi[j] = fmax(hi[j], q[j]);
    d.hmax = fmax(d.hmax, q[P_AMP]);
    d.rk_max = fmax(d.rk_max, q[P_RK]);
    rk_min = fmin(rk_min, q[P_RK]);
    f_max = fmax(f_max, q[P_F]);
    t_max = fmax(t_max, ta);
  }
  double range[KARST_I_DETAIL_PARAMS] = {0};
  if (amax > 0) {
    for (int j = 0; j < KARST_I_DETAIL_PARAMS; j++)
      d.bg[j] = 0.5 * (lo[j] + hi[j]);
    d.bg[P_AMP] = 0;
    lo[P_AMP] = 0;
    for (int k = 0; k < KARST_TUNNEL_TYPE_COUNT; k++)
      if (par->type[k].amplitude == 0) memcpy(d.param[k], d.bg, sizeof d.bg);
    for (int j = 0; j < KARST_I_DETAIL_PARAMS; j++)
      range[j] = hi[j] - lo[j];
  }
  d.seg = malloc((size_t)n_seg * sizeof *d.seg);
  if (!d.seg) return karst_set_error(ctx, KARST_ENOMEM, "details: out of memory");
  d.n_seg = n_seg;
  double r_min_seg = INFINITY;
  for (karst_int_t i = 0; i < n_seg; i++) {
    karst_i_dseg_t *s = &d.seg[i];
    memcpy(s->a, seg[i].a, sizeof s->a);
    for (int a = 0; a < 3; a++)
      s->u[a] = seg[i].b[a] - seg[i].a[a];
    s->len = sqrt(karst_i_dot3(s->u, s->u));
    for (int a = 0; a < 3; a++)
      s->u[a] = s->len > 0 ? s->u[a] / s->len : 0; /* a point segment has no direction */
    s->support = seg[i].support;
    s->type = seg[i].type;
    r_min_seg = fmin(r_min_seg, s->support);
  }
  if ((err = build_grid(ctx, &d))) {
    karst_i_details_free(&d);
    return err;
  }
  if (d.hmax > 0) {
    d.lip = details_lipschitz(&d, range, r_min_seg, rk_min, f_max, t_max);
    d.rc = fmax(d.shell + d.hmax, par->band);
  } else {
    d.lip = 1;
    d.rc = 0;
  }
  if (karst_i_grow((void **)&t->details, &t->cap_details, t->n_details + 1, sizeof *t->details)) {
    karst_i_details_free(&d);
    return karst_set_error(ctx, KARST_ENOMEM, "details: out of memory");
  }
  karst_i_node_t *nd = NULL;
  if ((err = karst_i_sdf_new_node(ctx, t, KARST_SDF_DETAILS, &nd, node))) {
    karst_i_details_free(&d);
    return err;
  }
  const karst_i_node_t *c = &t->nodes[child];
  nd->u.warp.index = t->n_details;
  nd->label = c->label;
  /* f >= f_S - H >= sdbox(child box) - H: the solid lies within H of the child's box */
  nd->finite = c->finite;
  for (int i = 0; i < 3; i++) {
    nd->box[i] = c->box[i] - d.hmax;
    nd->box[i + 3] = c->box[i + 3] + d.hmax;
  }
  if (nd->finite) karst_i_pad_box(nd->box);
  t->details[t->n_details++] = d;
  return KARST_SUCCESS;
}

static const karst_i_details_t *details_of(const karst_sdf_t *t, karst_int_t node) {
  if (!t || node < 0 || node >= t->n_nodes || t->nodes[node].kind != KARST_SDF_DETAILS) return NULL;
  return &t->details[t->nodes[node].u.warp.index];
}

/** The Lipschitz factor of a details node (see implicit.h). O(1). */
double karst_sdf_details_lipschitz(const karst_sdf_t *t, karst_int_t node) {
  const karst_i_details_t *d = details_of(t, node);
  return d ? d->lip : 0;
}

/** The shell half-width of a details node (see implicit.h). O(1). */
double karst_sdf_details_shell(const karst_sdf_t *t, karst_int_t node) {
  const karst_i_details_t *d = details_of(t, node);
  return d ? d->shell : 0;
}

/** The noise of a details node at a surface point (see implicit.h). O(segments near p). */
double karst_sdf_details_noise(const karst_sdf_t *t, karst_int_t node, const double p[3],
                               double fr[3][3]) {
  const karst_i_details_t *d = details_of(t, node);
  if (!d || d->hmax == 0) return 0;
  local_t L;
  local_frame(t, d, p, karst_i_sdf_eval(t, d->child, p, INFINITY, NULL, NULL), &L, NULL);
  if (fr) {
    memcpy(fr[0], L.n, sizeof L.n);
    memcpy(fr[1], L.t, sizeof L.t);
    memcpy(fr[2], L.b, sizeof L.b);
  }
  const double *th = L.bl.theta;
  return gabor(d, L.ps, L.n, L.wa, th[P_KAP], th[P_F], th[P_RK]);
}

/* ---------------------------------------------------------------------- */
/* The band rescaling as a node of its own.                                */
/* ---------------------------------------------------------------------- */

double karst_i_rescale_eval(const karst_sdf_t *t, const karst_i_node_t *nd, const double p[3],
                            double ub, int *label, karst_int_t *touched) {
  double L = nd->u.rescale.lip, rc = nd->u.rescale.rc, off = rc * (1 - 1 / L);
  double cub = ub;
  if (isfinite(ub)) cub = fabs(ub) * L <= rc ? ub * L : (ub > 0 ? ub + off : ub - off);
  double x = karst_i_sdf_eval(t, nd->u.rescale.child, p, cub, label, touched);
  if (fabs(x) <= rc) return x / L;
  return x > 0 ? x - off : x + off;
}

karst_error_t karst_i_rescale(karst_ctx_t *ctx, karst_sdf_t *t, karst_int_t child, double lip,
                              double rc, karst_int_t *node) {
  if (child < 0 || child >= t->n_nodes || !(lip >= 1) || !(rc >= 0))
    return karst_set_error(ctx, KARST_EINVAL, "rescale: node %lld, factor %g, band %g",
                           (long long)child, lip, rc);
  karst_i_node_t *nd = NULL;
  karst_error_t err = karst_i_sdf_new_node(ctx, t, KARST_SDF_RESCALE, &nd, node);
  if (err) return err;
  const karst_i_node_t *c = &t->nodes[child];
  nd->u.rescale.child = child;
  nd->u.rescale.lip = lip;
  nd->u.rescale.rc = rc;
  nd->label = c->label;
  /* the rescaling maps the child's zero set onto itself and never moves a
   * value across 0: the box (the solid's) is the child's */
  nd->finite = c->finite;
  memcpy(nd->box, c->box, sizeof nd->box);
  return KARST_SUCCESS;
}

/** The band (rc) of a details node: the rescaling is linear within it. */
double karst_i_details_band(const karst_sdf_t *t, karst_int_t node) {
  const karst_i_details_t *d = details_of(t, node);
  return d ? d->rc : 0;
}
