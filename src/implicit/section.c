/* Cross-sections of conduits: closed curves of quadratic Bezier pieces and
 * their exact signed distance in the section plane (Paris et al. 2021,
 * §6.2 and Appendix C: distance to the contour, sign by crossing count). */
#include <math.h>
#include <string.h>

#include "implicit/implicit_internal.h"

/* min / max without the NaN rules of fmin / fmax, which the compiler cannot
 * inline (the fields never see NaN: inputs are checked when nodes are made). */
static inline double mn(double a, double b) {
  return a < b ? a : b;
}
static inline double mx(double a, double b) {
  return a > b ? a : b;
}

/* ---------------------------------------------------------------------- */
/* Building the built-in sections.                                         */
/* ---------------------------------------------------------------------- */

typedef struct {
  karst_section_t *s;
  int m; /* control points written */
} builder_t;

static void put(builder_t *b, double x, double y) {
  if (b->m < 2 * KARST_SECTION_MAX_PIECES) {
    b->s->cp[b->m][0] = x;
    b->s->cp[b->m][1] = y;
  }
  b->m++;
}

/* Straight piece from (x0,y0) to the next on-curve point (x1,y1): the off
 * point is the midpoint, so the quadratic degenerates to the segment. */
static void line_piece(builder_t *b, double x0, double y0, double x1, double y1) {
  put(b, x0, y0);
  put(b, 0.5 * (x0 + x1), 0.5 * (y0 + y1));
}

/* Elliptic arc (centre c, semi-axes rx, ry) from angle a0 to a1 in n pieces.
 * Each piece is the affine image of the quadratic that interpolates a circle
 * arc at its ends with tangent continuity (off point on the bisector at
 * 1/cos(half angle)). The end point of the arc is NOT written (it is the
 * start of the next piece). */
static void arc_pieces(builder_t *b, double cx, double cy, double rx, double ry, double a0,
                       double a1, int n) {
  double da = (a1 - a0) / n;
  double k = 1.0 / cos(0.5 * da);
  for (int i = 0; i < n; i++) {
    double t0 = a0 + i * da, tm = t0 + 0.5 * da;
    put(b, cx + rx * cos(t0), cy + ry * sin(t0));
    put(b, cx + rx * k * cos(tm), cy + ry * k * sin(tm));
  }
}

/**
 * The unit cross-section of a tunnel type, in units of the conduit radius
 * (Paris et al. 2021, §5.3, Fig. 11–12: tube, keyhole, canyon, bed, passage,
 * epikarst; chambers are ellipsoids and get the tube here). Every built-in
 * section has 8 quadratic pieces so that sections can be interpolated.
 * @param ctx          error context
 * @param tunnel_type  a karst_tunnel_type_t value
 * @param out          the section
 * @return KARST_SUCCESS, or KARST_EINVAL for an unknown type.
 * Time complexity: O(1).
 */
karst_error_t karst_section_for_type(karst_ctx_t *ctx, int tunnel_type, karst_section_t *out) {
  if (!out) return karst_set_error(ctx, KARST_EINVAL, "section: no output given");
  memset(out, 0, sizeof *out);
  builder_t b = {out, 0};
  const double pi = M_PI;
  switch (tunnel_type) {
  case KARST_TUNNEL_TUBE:
  case KARST_TUNNEL_CHAMBER:
    /* Circle of radius 1, joints off the axes (22.5° + k 45°). */
    arc_pieces(&b, 0, 0, 1, 1, pi / 8, pi / 8 + 2 * pi, 8);
    break;
  case KARST_TUNNEL_KEYHOLE: {
    /* Phreatic tube (radius 0.8, centre 0.35 up) above a vadose slot 0.5 wide
     * reaching 1 below the axis (the keyhole of vadose entrenchment). */
    double rc = 0.8, cy = 0.35, hw = 0.25;
    double ys = cy - sqrt(rc * rc - hw * hw); /* where the slot meets the tube */
    double a = atan2(ys - cy, hw);
    line_piece(&b, hw, -1.0, hw, ys);
    arc_pieces(&b, 0, cy, rc, rc, a, pi - a, 5); /* a < 0: over the top */
    line_piece(&b, -hw, ys, -hw, -1.0);
    line_piece(&b, -hw, -1.0, hw, -1.0);
    break;
  }
  case KARST_TUNNEL_CANYON:
    /* Tall and narrow: rounded roof (radius 0.4 at 1.1 up), walls narrowing to
     * a rounded floor (radius 0.3 at 1.1 down). */
    arc_pieces(&b, 0, 1.1, 0.4, 0.4, 0, pi, 3);
    line_piece(&b, -0.4, 1.1, -0.3, -1.1);
    arc_pieces(&b, 0, -1.1, 0.3, 0.3, pi, 2 * pi, 3);
    line_piece(&b, 0.3, -1.1, 0.4, 1.1);
    break;
  case KARST_TUNNEL_BED:
    /* Wide and low along a bedding plane: ellipse 1.6 x 0.45. */
    arc_pieces(&b, 0, 0, 1.6, 0.45, pi / 8, pi / 8 + 2 * pi, 8);
    break;
  case KARST_TUNNEL_PASSAGE:
    /* Flat floor, vertical walls, elliptic roof. */
    line_piece(&b, -1.0, -0.6, 0.0, -0.6);
    line_piece(&b, 0.0, -0.6, 1.0, -0.6);
    line_piece(&b, 1.0, -0.6, 1.0, 0.2);
    arc_pieces(&b, 0, 0.2, 1.0, 0.6, 0, pi, 4);
    line_piece(&b, -1.0, 0.2, -1.0, -0.6);
    break;
  case KARST_TUNNEL_EPIKARST:
    /* Narrow fissure: ellipse 0.6 x 1.3. */
    arc_pieces(&b, 0, 0, 0.6, 1.3, pi / 8, pi / 8 + 2 * pi, 8);
    break;
  default:
    return karst_set_error(ctx, KARST_EINVAL, "section: unknown tunnel type %d (expected 0..%d)",
                           tunnel_type, KARST_TUNNEL_TYPE_COUNT - 1);
  }
  out->n = b.m / 2;
  if (b.m != 16)
    return karst_set_error(ctx, KARST_EINVAL, "section of type %d has %d control points, not 16",
                           tunnel_type, b.m);
  return KARST_SUCCESS;
}

/**
 * Exact area enclosed by a section: Green's theorem, each quadratic piece
 * contributing (2 P0xP1 + 2 P1xP2 + P0xP2) / 6 (x: 2-D cross product).
 * @param s a section
 * @return the (unsigned) area in squared radius units.
 * Time complexity: O(pieces).
 */
double karst_section_area(const karst_section_t *s) {
  double a = 0;
  for (int k = 0; k < s->n; k++) {
    const double *p0 = s->cp[2 * k], *p1 = s->cp[2 * k + 1], *p2 = s->cp[(2 * k + 2) % (2 * s->n)];
    double c01 = p0[0] * p1[1] - p0[1] * p1[0];
    double c12 = p1[0] * p2[1] - p1[1] * p2[0];
    double c02 = p0[0] * p2[1] - p0[1] * p2[0];
    a += (2 * c01 + 2 * c12 + c02) / 6.0;
  }
  return fabs(a);
}

/**
 * Check a section: piece count in 2..KARST_SECTION_MAX_PIECES, finite control
 * points, non-zero enclosed area.
 * @return KARST_SUCCESS or KARST_EINVAL naming the offending value.
 * Time complexity: O(pieces).
 */
karst_error_t karst_section_check(karst_ctx_t *ctx, const karst_section_t *s) {
  if (!s) return karst_set_error(ctx, KARST_EINVAL, "section: none given");
  if (s->n < 2 || s->n > KARST_SECTION_MAX_PIECES)
    return karst_set_error(ctx, KARST_EINVAL, "section: %d pieces, expected 2..%d", s->n,
                           KARST_SECTION_MAX_PIECES);
  for (int i = 0; i < 2 * s->n; i++)
    if (!isfinite(s->cp[i][0]) || !isfinite(s->cp[i][1]))
      return karst_set_error(ctx, KARST_EINVAL, "section: control point %d is not finite (%g, %g)",
                             i, s->cp[i][0], s->cp[i][1]);
  double area = karst_section_area(s);
  if (!(area > 0))
    return karst_set_error(ctx, KARST_EINVAL, "section: enclosed area is %g, must be > 0", area);
  return KARST_SUCCESS;
}

/**
 * Interpolate two sections control point by control point.
 * @param a, b  sections with the same number of pieces
 * @param t     in [0, 1]
 * @param out   (1 - t) a + t b
 * @return KARST_SUCCESS, or KARST_EINVAL when the piece counts differ or t is out of range.
 * Time complexity: O(pieces).
 */
karst_error_t karst_section_lerp(karst_ctx_t *ctx, const karst_section_t *a,
                                 const karst_section_t *b, double t, karst_section_t *out) {
  if (a->n != b->n)
    return karst_set_error(ctx, KARST_EINVAL,
                           "section interpolation: %d pieces against %d, must be equal", a->n,
                           b->n);
  if (!(t >= 0 && t <= 1))
    return karst_set_error(ctx, KARST_EINVAL, "section interpolation: t = %g not in [0, 1]", t);
  karst_section_t r;
  memset(&r, 0, sizeof r);
  r.n = a->n;
  for (int i = 0; i < 2 * a->n; i++)
    for (int c = 0; c < 2; c++)
      r.cp[i][c] = (1 - t) * a->cp[i][c] + t * b->cp[i][c];
  *out = r;
  return KARST_SUCCESS;
}

/* ---------------------------------------------------------------------- */
/* Distance to one quadratic piece.                                        */
/* ---------------------------------------------------------------------- */

/* Leading coefficients below this fraction of the others are treated as zero
 * (the cubic degenerates to a quadratic, e.g. on straight pieces whose off
 * point is the midpoint). Only affects which closed form is used; every
 * candidate is polished by Newton steps and the endpoints are always tried. */
#define CUBIC_DEGENERATE 1e-12

/* Real roots of c3 t^3 + c2 t^2 + c1 t + c0 (Cardano / trigonometric form). */
static int solve_cubic(double c3, double c2, double c1, double c0, double r[3]) {
  double scale = fabs(c2) + fabs(c1) + fabs(c0);
  if (fabs(c3) <= CUBIC_DEGENERATE * scale) {
    if (fabs(c2) <= CUBIC_DEGENERATE * (fabs(c1) + fabs(c0))) {
      if (c1 == 0) return 0;
      r[0] = -c0 / c1;
      return 1;
    }
    double disc = c1 * c1 - 4 * c2 * c0;
    if (disc < 0) return 0;
    double sq = sqrt(disc);
    double qq = -0.5 * (c1 + (c1 >= 0 ? sq : -sq));
    int n = 0;
    if (qq != 0) r[n++] = c0 / qq;
    r[n++] = qq / c2;
    return n;
  }
  double A = c2 / c3, B = c1 / c3, C = c0 / c3;
  double p = B - A * A / 3.0, q = 2.0 * A * A * A / 27.0 - A * B / 3.0 + C;
  double off = -A / 3.0;
  double disc = 0.25 * q * q + p * p * p / 27.0;
  if (disc >= 0) {
    double sq = sqrt(disc);
    r[0] = cbrt(-0.5 * q + sq) + cbrt(-0.5 * q - sq) + off;
    return 1;
  }
  double m = 2.0 * sqrt(-p / 3.0);
  double arg = 3.0 * q / (p * m);
  arg = arg < -1 ? -1 : (arg > 1 ? 1 : arg);
  double th = acos(arg) / 3.0;
  for (int k = 0; k < 3; k++)
    r[k] = m * cos(th - 2.0 * M_PI * k / 3.0) + off;
  return 3;
}

/* Squared distance from q to the quadratic Bezier p0, p1, p2. */
static double bezier_dist2(const double *p0, const double *p1, const double *p2, const double *q) {
  /* B(t) - q = c + 2 a t + b t^2 ; stationary points of |B - q|^2 solve
   * (b.b) t^3 + 3 (a.b) t^2 + (2 a.a + c.b) t + c.a = 0. */
  double ax = p1[0] - p0[0], ay = p1[1] - p0[1];
  double bx = p0[0] - 2 * p1[0] + p2[0], by = p0[1] - 2 * p1[1] + p2[1];
  double cx = p0[0] - q[0], cy = p0[1] - q[1];
  double best = cx * cx + cy * cy;
  double ex = p2[0] - q[0], ey = p2[1] - q[1];
  double d1 = ex * ex + ey * ey;
  if (d1 < best) best = d1;
  double k3 = bx * bx + by * by, k2 = 3 * (ax * bx + ay * by);
  double k1 = 2 * (ax * ax + ay * ay) + cx * bx + cy * by, k0 = cx * ax + cy * ay;
  double r[3];
  int n = solve_cubic(k3, k2, k1, k0, r);
  for (int i = 0; i < n; i++) {
    double t = r[i];
    /* Two Newton steps on g(t) = (B - q).B'/2 polish roots lost to cancellation. */
    for (int it = 0; it < 2; it++) {
      double g = ((k3 * t + k2) * t + k1) * t + k0;
      double dg = (3 * k3 * t + 2 * k2) * t + k1;
      if (dg == 0) break;
      double tn = t - g / dg;
      if (!isfinite(tn)) break;
      t = tn;
    }
    if (!(t > 0 && t < 1)) continue;
    double x = cx + 2 * ax * t + bx * t * t, y = cy + 2 * ay * t + by * t * t;
    double d = x * x + y * y;
    if (d < best) best = d;
  }
  return best;
}

/* Squared distance from q to the segment p0 p2. */
static double segment_dist2(const double *p0, const double *p2, const double *q) {
  double ux = p2[0] - p0[0], uy = p2[1] - p0[1], vx = q[0] - p0[0], vy = q[1] - p0[1];
  double uu = ux * ux + uy * uy, t = uu > 0 ? (vx * ux + vy * uy) / uu : 0;
  t = t < 0 ? 0 : (t > 1 ? 1 : t);
  double dx = vx - t * ux, dy = vy - t * uy;
  return dx * dx + dy * dy;
}

/* Lower bound of the squared distance from q to the convex hull (box) of the piece. */
static double hull_box_dist2(const double *p0, const double *p1, const double *p2,
                             const double *q) {
  double d = 0;
  for (int c = 0; c < 2; c++) {
    double lo = mn(p0[c], mn(p1[c], p2[c])), hi = mx(p0[c], mx(p1[c], p2[c]));
    double e = q[c] < lo ? lo - q[c] : (q[c] > hi ? q[c] - hi : 0);
    d += e * e;
  }
  return d;
}

/* x of the piece at B_y(t) = y on the y-monotone part [t0, t1]. */
static double crossing_x(const double *p0, const double *p1, const double *p2, double t0, double t1,
                         double y) {
  double a = p0[1] - 2 * p1[1] + p2[1], b = 2 * (p1[1] - p0[1]), c = p0[1] - y;
  double t;
  if (fabs(a) <= CUBIC_DEGENERATE * (fabs(b) + fabs(c))) {
    t = b != 0 ? -c / b : 0.5 * (t0 + t1);
  } else {
    double disc = b * b - 4 * a * c;
    if (disc < 0) disc = 0;
    double sq = sqrt(disc);
    double qq = -0.5 * (b + (b >= 0 ? sq : -sq));
    double r0 = qq != 0 ? c / qq : 0.5 * (t0 + t1), r1 = qq / a;
    /* the root inside (or nearest to) the monotone interval */
    double e0 = r0 < t0 ? t0 - r0 : (r0 > t1 ? r0 - t1 : 0);
    double e1 = r1 < t0 ? t0 - r1 : (r1 > t1 ? r1 - t1 : 0);
    t = e0 <= e1 ? r0 : r1;
  }
  if (t < t0) t = t0;
  if (t > t1) t = t1;
  return (1 - t) * (1 - t) * p0[0] + 2 * t * (1 - t) * p1[0] + t * t * p2[0];
}

/* Number of crossings (mod 2) of the ray from q towards +x with the piece.
 * The piece is cut into y-monotone parts and each part counts with the
 * half-open rule of polygon crossing tests (one end above q, the other not),
 * with the end values shared exactly between neighbouring parts and pieces,
 * so grazing and horizontal parts are counted consistently. */
static int piece_crossings(const double *p0, const double *p1, const double *p2, const double *q) {
  double ylo = mn(p0[1], mn(p1[1], p2[1])), yhi = mx(p0[1], mx(p1[1], p2[1]));
  if (q[1] < ylo || q[1] > yhi) return 0;
  if (q[0] > mx(p0[0], mx(p1[0], p2[0]))) return 0;
  double ts[3] = {0, 1, 1}, ys[3] = {p0[1], p2[1], p2[1]};
  int nparts = 1;
  double den = p0[1] - 2 * p1[1] + p2[1];
  if (den != 0) {
    double tm = (p0[1] - p1[1]) / den;
    if (tm > 0 && tm < 1) {
      ts[1] = tm;
      ys[1] = (1 - tm) * (1 - tm) * p0[1] + 2 * tm * (1 - tm) * p1[1] + tm * tm * p2[1];
      nparts = 2;
    }
  }
  int count = 0;
  for (int k = 0; k < nparts; k++) {
    double y0 = ys[k], y1 = ys[k + 1];
    if ((y0 > q[1]) == (y1 > q[1])) continue;
    double x = crossing_x(p0, p1, p2, ts[k], ts[k + 1], q[1]);
    if (x > q[0]) count++;
  }
  return count;
}

/**
 * Signed distance from @p q to a section in its plane (Appendix C): the
 * Euclidean distance to the closest quadratic piece (roots of the cubic of
 * stationary points, plus the ends), negative when the crossing count of a
 * ray from q is odd. Exact, hence 1-Lipschitz in the plane.
 * Time complexity: O(pieces).
 */
double karst_section_distance(const karst_section_t *s, const double q[2]) {
  double best = INFINITY, box[KARST_SECTION_MAX_PIECES];
  int cross = 0, order[KARST_SECTION_MAX_PIECES];
  int m = 2 * s->n;
  /* nearest hull boxes first, so that the others are mostly pruned */
  for (int k = 0; k < s->n; k++) {
    const double *p0 = s->cp[2 * k], *p1 = s->cp[2 * k + 1], *p2 = s->cp[(2 * k + 2) % m];
    cross += piece_crossings(p0, p1, p2, q);
    box[k] = hull_box_dist2(p0, p1, p2, q);
    int at = k;
    while (at > 0 && box[order[at - 1]] > box[k]) {
      order[at] = order[at - 1];
      at--;
    }
    order[at] = k;
  }
  for (int i = 0; i < s->n; i++) {
    int k = order[i];
    if (box[k] >= best) break;
    const double *p0 = s->cp[2 * k], *p1 = s->cp[2 * k + 1], *p2 = s->cp[(2 * k + 2) % m];
    double d;
    if (p1[0] == 0.5 * (p0[0] + p2[0]) && p1[1] == 0.5 * (p0[1] + p2[1])) {
      d = segment_dist2(p0, p2, q); /* a straight piece: no cubic to solve */
    } else {
      d = bezier_dist2(p0, p1, p2, q);
    }
    if (d < best) best = d;
  }
  double d = sqrt(best);
  return (cross & 1) ? -d : d;
}
