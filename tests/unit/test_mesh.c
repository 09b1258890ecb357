/* Polygonizer and mesh writers (src/mesh/): closed, 2-manifold, consistently
 * oriented meshes (own combinatorial check and CGAL's, independently), volumes
 * against closed forms, determinism across thread counts, Lipschitz skipping,
 * the PLY / STL files. */
#include <dirent.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "karst.h"
#include "mesh/mesh_internal.h"
#include "sdf_check.h"
#include "test_util.h"

/* Shortest triangle side of a mesh, in metres. */
static double shortest_side(const karst_mesh_t *m) {
  double best = INFINITY;
  for (karst_int_t i = 0; i < m->n_triangles; i++)
    for (int k = 0; k < 3; k++) {
      const double *p = m->xyz + 3 * m->tri[3 * i + k],
                   *q = m->xyz + 3 * m->tri[3 * i + (k + 1) % 3];
      best = fmin(best, sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                             (p[2] - q[2]) * (p[2] - q[2])));
    }
  return best;
}

/* Closed, manifold, consistently and outward oriented, by both checks, no
 * triangle with a zero side (KARST_MESH_EDGE_MARGIN), and CGAL's volume equal to ours (both are the
 * divergence theorem on the same triangles: they agree to rounding, 1e-9 relative). Returns the
 * volume. */
static double assert_good_mesh(const karst_mesh_t *m) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_mesh_check_t chk;
  assert_int_equal(karst_mesh_check(&ctx, m, &chk), KARST_SUCCESS);
  assert_int_equal(chk.boundary_edges, 0);
  assert_int_equal(chk.nonmanifold_edges, 0);
  assert_int_equal(chk.degenerate, 0);
  assert_true(shortest_side(m) > 0);
  karst_i_cgal_report_t rep;
  char err[256] = "";
  assert_int_equal(
      karst_i_cgal_check_mesh(m->xyz, m->n_vertices, m->tri, m->n_triangles, &rep, err, sizeof err),
      0);
  assert_true(rep.is_polygon_mesh);
  assert_true(rep.closed);
  assert_true(rep.outward);
  double v = karst_mesh_volume(m);
  assert_rel(rep.volume, v, 1e-9);
  return v;
}

static karst_sdf_t *tube_tree(double r, const double a[3], const double b[3], int type) {
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  karst_section_t s;
  karst_section_for_type(&ctx, type, &s);
  karst_int_t id;
  assert_int_equal(karst_sdf_sweep(&ctx, t, a, b, &s, r, NULL, NULL, type, &id), KARST_SUCCESS);
  karst_sdf_set_root(&ctx, t, id);
  return t;
}

/* A straight tube, r = 2 m, L = 10 m, tilted off the grid axes, at voxel
 * h = 0.2 m. Expected volume: the exact area of its section (Green's theorem
 * on the 8 quadratics, 1.0055 π r² — the quadratics bulge 0.3 % past the
 * circle between joints) times L.
 * Bound of the voxel error: every mesh vertex is the zero of the linear
 * interpolant along a grid edge of length <= √3 h, so it lies within
 * κ (√3 h)²/8 of the surface where the field has curvature κ, and a triangle
 * (sides <= √3 h) sags at most κ (√3 h)²/8 more: on the wall (κ = 1/r) the
 * surface moves by at most 3h²/(4r) over the area 2πrL. Near the two rims the
 * field has a kink; there the error is at most the √3 h band: 2 · 2πr · 3h².
 * |ΔV| <= 2πrL · 3h²/(4r) + 4πr · 3h² = 1.885 + 3.016 = 4.90 m³ (3.9 %). */
static void test_tube_volume(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = 2;
  const double r = 2, L = 10, h = 0.2;
  double dir[3] = {0.8, 0.36, 0.48}; /* unit */
  double a[3] = {1, 2, 3}, b[3];
  for (int c = 0; c < 3; c++)
    b[c] = a[c] + L * dir[c];
  karst_sdf_t *t = tube_tree(r, a, b, KARST_TUNNEL_TUBE);
  double box[6] = {-3, -3, -3, 14, 10, 12};
  karst_mesh_t m;
  karst_mesh_init(&m);
  karst_polygonize_stats_t st;
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, h, &m, &st), KARST_SUCCESS);
  double v = assert_good_mesh(&m);
  karst_section_t s;
  karst_section_for_type(&ctx, KARST_TUNNEL_TUBE, &s);
  double exact = karst_section_area(&s) * r * r * L;
  double bound = 2 * M_PI * r * L * 3 * h * h / (4 * r) + 4 * M_PI * r * 3 * h * h;
  printf("tube: V = %.4f m3, exact %.4f (pi r^2 L = %.4f), error %.3f %% (bound %.2f m3 = "
         "%.1f %%); %lld triangles, %lld of %lld blocks skipped, %lld evaluations for %lld grid "
         "points\n",
         v, exact, M_PI * r * r * L, 100 * (v - exact) / exact, bound, 100 * bound / exact,
         (long long)m.n_triangles, (long long)st.n_skipped, (long long)st.n_blocks,
         (long long)st.n_evals,
         (long long)((st.cells[0] + 1) * (st.cells[1] + 1) * (st.cells[2] + 1)));
  assert_close(v, exact, bound);
  assert_close(v, M_PI * r * r * L, bound + exact - M_PI * r * r * L);
  /* every triangle carries the tube's label */
  for (karst_int_t i = 0; i < m.n_triangles; i++)
    assert_int_equal(m.tri_label[i], KARST_TUNNEL_TUBE);
  assert_string_equal(m.tri_label_name, "tunnel_type");
  karst_mesh_destroy(&m);
  karst_sdf_free(t);
}

/* A sphere: 4/3 π r³ within the same wall bound (κ = 1/r, area 4πr², no rim). */
static void test_sphere_volume(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  double c[3] = {0.13, 0.27, -0.31};
  const double r = 3, h = 0.25;
  karst_int_t id;
  karst_sdf_sphere(&ctx, t, c, r, 2, &id);
  karst_sdf_set_root(&ctx, t, id);
  double box[6] = {-5, -5, -5, 5, 5, 5};
  karst_mesh_t m;
  karst_mesh_init(&m);
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, h, &m, NULL), KARST_SUCCESS);
  double v = assert_good_mesh(&m);
  double exact = 4.0 / 3.0 * M_PI * r * r * r;
  double bound = 4 * M_PI * r * r * 3 * h * h / (4 * r);
  printf("sphere: V = %.4f, exact %.4f, error %.3f %% (bound %.2f %%)\n", v, exact,
         100 * (v - exact) / exact, 100 * bound / exact);
  assert_close(v, exact, bound);
  karst_mesh_destroy(&m);
  karst_sdf_free(t);
}

/* Clipping keeps the mesh closed: a solid that fills the whole box gives the
 * surface of the clip box (the box shrunk by h/2), whose field is linear
 * across each face, so the faces are exact; only the edges and corners,
 * where the box distance has a kink, are cut by at most the √3 h band
 * (12 edges: Σ edge lengths · 3h²). A tube running out of the box is closed
 * by the box faces. */
static void test_clip_closed(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  double c[3] = {0, 0, 0};
  karst_int_t id;
  karst_sdf_sphere(&ctx, t, c, 100, 0, &id);
  karst_sdf_set_root(&ctx, t, id);
  const double h = 0.5;
  double box[6] = {-4, -3, -2, 4, 3, 2};
  karst_mesh_t m;
  karst_mesh_init(&m);
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, h, &m, NULL), KARST_SUCCESS);
  double v = assert_good_mesh(&m);
  double exact = (8 - h) * (6 - h) * (4 - h);
  double bound = 4 * ((8 - h) + (6 - h) + (4 - h)) * 3 * h * h;
  printf("clip box: V = %.4f, exact %.4f (bound %.3f)\n", v, exact, bound);
  assert_close(v, exact, bound);
  for (karst_int_t i = 0; i < m.n_triangles; i++)
    assert_int_equal(m.tri_label[i], KARST_SDF_NO_LABEL);
  karst_sdf_free(t);

  /* a canyon along x, longer than the box: closed by the box faces; its
   * volume is the section area times the clipped length 20 - h, within the
   * wall and rim bounds of the tube test (κ <= 1/(0.3 r) on the canyon's
   * tightest round, r = 1.5) */
  double a[3] = {-20, 0.1, 0.05}, b[3] = {20, 0.1, 0.05};
  t = tube_tree(1.5, a, b, KARST_TUNNEL_CANYON);
  double box2[6] = {-10, -4, -4, 10, 4, 4};
  const double h2 = 0.2;
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box2, h2, &m, NULL), KARST_SUCCESS);
  v = assert_good_mesh(&m);
  karst_section_t s;
  karst_section_for_type(&ctx, KARST_TUNNEL_CANYON, &s);
  double area = karst_section_area(&s) * 1.5 * 1.5;
  double per =
      2 * M_PI * 1.5 * 1.5; /* perimeter bound: the canyon fits the circle of radius 1.5 r */
  exact = area * (20 - h2);
  bound = per * 20 * 3 * h2 * h2 / (4 * 0.3 * 1.5) + 2 * per * 3 * h2 * h2;
  printf("clipped canyon: V = %.4f, exact %.4f, error %.3f %% (bound %.2f %%)\n", v, exact,
         100 * (v - exact) / exact, 100 * bound / exact);
  assert_close(v, exact, bound);
  int canyon = 0, clip = 0;
  for (karst_int_t i = 0; i < m.n_triangles; i++) {
    canyon += m.tri_label[i] == KARST_TUNNEL_CANYON;
    clip += m.tri_label[i] == KARST_SDF_NO_LABEL;
  }
  assert_true(canyon > 0 && clip > 0 && canyon + clip == m.n_triangles);
  karst_mesh_destroy(&m);
  karst_sdf_free(t);
}

/* The same mesh, array for array, with 1 and 2 threads. */
static void test_deterministic(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  double a[3] = {0, 0, 0}, b[3] = {30, 10, 3};
  karst_sdf_t *t = tube_tree(2.5, a, b, KARST_TUNNEL_KEYHOLE);
  double box[6] = {-4, -4, -4, 34, 14, 7};
  karst_mesh_t m1, m2;
  karst_mesh_init(&m1);
  karst_mesh_init(&m2);
  assert_same_on_1_and_2_threads(t, box, 0.3, &m1, &m2);
  assert_good_mesh(&m1);
  karst_mesh_destroy(&m1);
  karst_mesh_destroy(&m2);
  karst_sdf_free(t);
}

/* Cost grows with the surface, not the volume: the same sphere in a box
 * 4 times wider (64 times the volume) costs fewer than 1.5 times the field
 * evaluations, and the evaluations are a small fraction of the grid points.
 * An empty box gives an empty mesh. */
static void test_skipping(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  double c[3] = {0.1, 0.2, 0.3};
  karst_int_t id;
  karst_sdf_sphere(&ctx, t, c, 2, 0, &id);
  karst_sdf_set_root(&ctx, t, id);
  double small[6] = {-8, -8, -8, 8, 8, 8}, big[6] = {-32, -32, -32, 32, 32, 32};
  karst_mesh_t m;
  karst_mesh_init(&m);
  karst_polygonize_stats_t s1, s2;
  assert_int_equal(karst_mesh_polygonize(&ctx, t, small, 0.25, &m, &s1), KARST_SUCCESS);
  karst_int_t tri = m.n_triangles;
  assert_int_equal(karst_mesh_polygonize(&ctx, t, big, 0.25, &m, &s2), KARST_SUCCESS);
  assert_int_equal(m.n_triangles, tri);
  double pts = 257.0 * 257 * 257;
  printf("skipping: %lld evaluations in the small box, %lld in the 64x larger one (%.2f %% of its "
         "%.0f grid points); %lld of %lld blocks skipped\n",
         (long long)s1.n_evals, (long long)s2.n_evals, 100.0 * s2.n_evals / pts, pts,
         (long long)s2.n_skipped, (long long)s2.n_blocks);
  assert_true(s2.n_evals < 1.5 * s1.n_evals);
  assert_true(s2.n_evals < 0.01 * pts);
  /* nothing in the box */
  double empty[6] = {20, 20, 20, 30, 30, 30};
  assert_int_equal(karst_mesh_polygonize(&ctx, t, empty, 0.5, &m, NULL), KARST_SUCCESS);
  assert_int_equal(m.n_triangles, 0);
  assert_int_equal(m.n_vertices, 0);
  assert_close(karst_mesh_volume(&m), 0, 0);
  karst_mesh_destroy(&m);
  karst_sdf_free(t);
}

/* A network with a sharp bend (Poisson spheres), a mitred joint, a junction
 * and a chamber, carved from a flat terrain at z = 4: closed and manifold by
 * both checks. The rock volume is the clip box below the terrain minus the
 * caves below it, so it must be less than the first and more than the first
 * minus the conduits' own mesh volume... the conduits are meshed separately. */
static void test_network_mesh(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  ctx.nthreads = 2;
  karst_network_t net;
  karst_network_init(&net);
  double P[][3] = {{0, 0, 0},   {15, 0, 0},   {15 + 15 * cos(0.5), 15 * sin(0.5), 1},
                   {20, 20, 0}, {10, 25, -3}, {30, 25, 0},
                   {20, 35, 2}};
  for (int i = 0; i < 7; i++)
    karst_network_add_node(&net, P[i][0], P[i][1], P[i][2], NULL);
  karst_int_t E[][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 4}, {3, 5}, {3, 6}};
  for (int e = 0; e < 6; e++)
    karst_network_add_edge(&net, E[e][0], E[e][1], NULL);
  double *rad, *typ;
  karst_network_attr_add(&net, KARST_ATTR_EDGE, "radius", 1, 0, &rad);
  karst_network_attr_add(&net, KARST_ATTR_EDGE, "tunnel_type", 1, 1, &typ);
  const int types[6] = {KARST_TUNNEL_TUBE,   KARST_TUNNEL_PASSAGE, KARST_TUNNEL_KEYHOLE,
                        KARST_TUNNEL_CANYON, KARST_TUNNEL_CHAMBER, KARST_TUNNEL_BED};
  for (int e = 0; e < 6; e++)
    rad[e] = 1.2, typ[e] = types[e];
  karst_implicit_params_t par;
  karst_implicit_params_init(&par);
  par.noise_amplitude = 0.2;
  par.noise_wavelength = 1.5;
  karst_sdf_t *t;
  double box[6] = {-3, -4, -8, 34, 40, 6};
  karst_mesh_t m;
  karst_mesh_init(&m);
  double vc = 0;
  /* sharp bends filled with Poisson spheres, then revolved (the default) */
  for (int mode = 1; mode >= 0; mode--) {
    par.bend_spheres = mode;
    karst_sdf_create(&ctx, &t);
    karst_implicit_stats_t bst;
    assert_int_equal(karst_implicit_build(&ctx, &net, &par, NULL, t, &bst), KARST_SUCCESS);
    assert_true(bst.n_bends >= 1 && bst.n_mitred_ends >= 2);
    assert_true(mode ? bst.n_spheres > 0 : bst.n_revolves > 0);
    assert_int_equal(karst_mesh_polygonize(&ctx, t, box, 0.25, &m, NULL), KARST_SUCCESS);
    vc = assert_good_mesh(&m);
    int seen[KARST_TUNNEL_TYPE_COUNT] = {0};
    for (karst_int_t i = 0; i < m.n_triangles; i++)
      if (m.tri_label[i] >= 0) seen[m.tri_label[i]] = 1;
    for (int e = 0; e < 6; e++)
      assert_true(seen[types[e]]);
    karst_sdf_free(t);
  }

  karst_terrain_t flat;
  memset(&flat, 0, sizeof flat);
  flat.elevation = 4;
  karst_sdf_create(&ctx, &t);
  assert_int_equal(karst_implicit_build(&ctx, &net, &par, &flat, t, NULL), KARST_SUCCESS);
  karst_mesh_t r;
  karst_mesh_init(&r);
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, 0.25, &r, NULL), KARST_SUCCESS);
  double vr = assert_good_mesh(&r);
  /* rock = (clip box below z = 4) minus the caves; the caves lie below z = 4
   * except where they reach the surface, so vr ≈ slab - vc within the voxel bands */
  /* the ground z = 4 lies on grid points (field 0, counted as air): its
   * vertices sit KARST_MESH_EDGE_MARGIN of a voxel below it */
  double slab = (37 - 0.25) * (44 - 0.25) * (4 + 8 - 0.125 - KARST_MESH_EDGE_MARGIN * 0.25);
  printf("network: caves %.1f m3 (%lld triangles), rock %.1f m3, slab %.1f m3\n", vc,
         (long long)m.n_triangles, vr, slab);
  assert_rel(vr, slab - vc, 0.01);
  karst_mesh_destroy(&m);
  karst_mesh_destroy(&r);
  karst_sdf_free(t);
  karst_network_destroy(&net);
}

/* A sphere of radius 3 m centred on a grid point of a 0.25 m grid passes
 * exactly through grid points (±3 m = 12 voxels along each axis), where all
 * edges meeting there used to put their vertex: 300 of 15 840 triangles had a
 * zero side. With the margin, two vertices on edges sharing a grid point are
 * at least m h sin 35.26° apart (the smallest angle between Kuhn edges, face
 * and body diagonals: cos = 2/√6), and vertices on opposite edges of a
 * tetrahedron are farther: bound 0.01 × 0.25 × 0.577 = 1.44 mm. */
static void test_no_collapsed_triangles(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  const double c[3] = {0, 0, 0}, h = 0.25;
  karst_int_t id;
  karst_sdf_sphere(&ctx, t, c, 3, KARST_TUNNEL_TUBE, &id);
  karst_sdf_set_root(&ctx, t, id);
  double box[6] = {-4, -4, -4, 4, 4, 4};
  karst_mesh_t m;
  karst_mesh_init(&m);
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, h, &m, NULL), KARST_SUCCESS);
  assert_good_mesh(&m);
  double bound = KARST_MESH_EDGE_MARGIN * h * sqrt(1 - 4.0 / 6.0);
  double s = shortest_side(&m);
  printf("sphere on grid points: %lld triangles, shortest side %.3g m (bound %.3g m)\n",
         (long long)m.n_triangles, s, bound);
  assert_true(s >= bound * (1 - 1e-9));
  karst_mesh_destroy(&m);
  karst_sdf_free(t);
}

/* PLY and STL files: sizes and contents read back; unknown extension fails;
 * a failed write leaves no file. */
static void test_writers(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  double a[3] = {0, 0, 0}, b[3] = {4, 0, 0};
  karst_sdf_t *t = tube_tree(1, a, b, KARST_TUNNEL_BED);
  double box[6] = {-2, -3, -2, 6, 3, 2};
  karst_mesh_t m;
  karst_mesh_init(&m);
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, 0.25, &m, NULL), KARST_SUCCESS);
  assert_true(m.n_triangles > 100);
  char dir[] = "/tmp/karst_mesh_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char ply[256], stl[256], bad[256];
  snprintf(ply, sizeof ply, "%s/cave.ply", dir);
  snprintf(stl, sizeof stl, "%s/cave.STL", dir);
  snprintf(bad, sizeof bad, "%s/cave.obj", dir);
  assert_int_equal(karst_mesh_write(&ctx, ply, &m), KARST_SUCCESS);
  assert_int_equal(karst_mesh_write(&ctx, stl, &m), KARST_SUCCESS);
  assert_int_equal(karst_mesh_write(&ctx, bad, &m), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, ".obj"));
  assert_int_equal(access(bad, F_OK), -1);

  /* STL: 84 + 50 T bytes, the count, the first vertex as float */
  FILE *f = fopen(stl, "rb");
  assert_non_null(f);
  fseek(f, 0, SEEK_END);
  assert_int_equal(ftell(f), 84 + 50 * m.n_triangles);
  unsigned char hb[84 + 50];
  fseek(f, 0, SEEK_SET);
  assert_int_equal(fread(hb, 1, sizeof hb, f), sizeof hb);
  fclose(f);
  uint32_t cnt = hb[80] | hb[81] << 8 | hb[82] << 16 | (uint32_t)hb[83] << 24;
  assert_int_equal(cnt, m.n_triangles);
  float x0;
  memcpy(&x0, hb + 84 + 12, 4); /* little-endian host */
  assert_close(x0, (float)m.xyz[3 * m.tri[0]], 0);

  /* PLY: header, then V * 24 + T * 21 bytes; check the last vertex and face */
  f = fopen(ply, "rb");
  assert_non_null(f);
  char line[256];
  long long nv = -1, nf = -1;
  int label_prop = 0;
  while (fgets(line, sizeof line, f)) {
    sscanf(line, "element vertex %lld", &nv);
    sscanf(line, "element face %lld", &nf);
    if (strcmp(line, "property int tunnel_type\n") == 0) label_prop = 1;
    if (strcmp(line, "end_header\n") == 0) break;
  }
  assert_int_equal(nv, m.n_vertices);
  assert_int_equal(nf, m.n_triangles);
  assert_true(label_prop);
  long body = ftell(f);
  fseek(f, 0, SEEK_END);
  assert_int_equal(ftell(f) - body, 24 * m.n_vertices + 21 * m.n_triangles);
  fseek(f, body + 24 * (m.n_vertices - 1), SEEK_SET);
  double xyz[3];
  assert_int_equal(fread(xyz, 8, 3, f), 3);
  for (int c = 0; c < 3; c++)
    assert_close(xyz[c], m.xyz[3 * (m.n_vertices - 1) + c], 0);
  fseek(f, -21, SEEK_END);
  unsigned char face[21];
  assert_int_equal(fread(face, 1, 21, f), 21);
  fclose(f);
  assert_int_equal(face[0], 3);
  int32_t idx[5];
  memcpy(idx, face + 1, 20);
  for (int k = 0; k < 3; k++)
    assert_int_equal(idx[k], m.tri[3 * (m.n_triangles - 1) + k]);
  assert_int_equal(idx[3], KARST_TUNNEL_BED);
  assert_int_equal(idx[4], KARST_SDF_FEATURE_WALL);
  remove(ply);
  remove(stl);
  rmdir(dir);
  karst_mesh_destroy(&m);
  karst_sdf_free(t);
}

/* The float32 vertices of a binary STL file, relative to the origin its
 * header declares ("karst origin x=.. y=.. z=.."); returns the triangle count. */
static long read_stl(const char *path, double origin[3], float **xyz) {
  FILE *f = fopen(path, "rb");
  assert_non_null(f);
  unsigned char head[84];
  assert_int_equal(fread(head, 1, 84, f), 84);
  char text[81];
  memcpy(text, head, 80);
  text[80] = '\0';
  assert_int_equal(
      sscanf(text, "karst origin x=%lf y=%lf z=%lf", &origin[0], &origin[1], &origin[2]), 3);
  long n = (long)(head[80] | head[81] << 8 | head[82] << 16 | (uint32_t)head[83] << 24);
  *xyz = malloc((size_t)n * 9 * sizeof **xyz);
  assert_non_null(*xyz);
  for (long t = 0; t < n; t++) {
    unsigned char r[50];
    assert_int_equal(fread(r, 1, 50, f), 50);
    memcpy(*xyz + 9 * t, r + 12, 36); /* little-endian host */
  }
  assert_int_equal(fgetc(f), EOF);
  fclose(f);
  return n;
}

/* Triangles of float32 corners (plus @p origin, in double) that are
 * degenerate: two corners equal, or a zero cross product. */
static long degenerate_float_triangles(const float *xyz, long n, const double origin[3]) {
  long bad = 0;
  for (long t = 0; t < n; t++) {
    double p[3][3];
    for (int k = 0; k < 3; k++)
      for (int c = 0; c < 3; c++)
        p[k][c] = (double)xyz[9 * t + 3 * k + c] + origin[c];
    double u[3], v[3];
    for (int c = 0; c < 3; c++)
      u[c] = p[1][c] - p[0][c], v[c] = p[2][c] - p[0][c];
    double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2],
           z = u[0] * v[1] - u[1] * v[0];
    if (x == 0 && y == 0 && z == 0) bad++;
  }
  return bad;
}

/* A mesh at UTM-like coordinates (easting 6e5 m, northing 5.1e6 m, where
 * float32 steps are 6 cm and 0.5 m): the STL declares the origin in its
 * header, expected by hand from the sphere's bounding box: x ≥ 600120.37 →
 * 600100, y ≥ 5123453.71 → 5123400, z within ±1000 m → 0; written vertices
 * plus that origin give the float64 vertices to 1 mm (the bound of the
 * brief; float32 over a 100 m range rounds by 4 µm at most), and no triangle
 * collapses. The same vertices cast to float32 without the origin would
 * fail both checks (asserted, so that the test can tell). The PLY stores
 * doubles: its vertices come back bit for bit. */
static void test_far_from_origin(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  const double c[3] = {600123.37, 5123456.71, 432.19}, r = 3;
  karst_int_t id;
  karst_sdf_sphere(&ctx, t, c, r, KARST_TUNNEL_TUBE, &id);
  karst_sdf_set_root(&ctx, t, id);
  double box[6];
  for (int a = 0; a < 3; a++)
    box[a] = c[a] - 4, box[a + 3] = c[a] + 4;
  karst_mesh_t m;
  karst_mesh_init(&m);
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, 0.25, &m, NULL), KARST_SUCCESS);
  assert_true(m.n_triangles > 1000);
  double o[3];
  karst_mesh_stl_origin(&m, o);
  assert_close(o[0], 600100, 0);
  assert_close(o[1], 5123400, 0);
  assert_close(o[2], 0, 0);

  char dir[] = "/tmp/karst_mesh_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char stl[256], ply[256];
  snprintf(stl, sizeof stl, "%s/far.stl", dir);
  snprintf(ply, sizeof ply, "%s/far.ply", dir);
  assert_int_equal(karst_mesh_write(&ctx, stl, &m), KARST_SUCCESS);
  assert_int_equal(karst_mesh_write(&ctx, ply, &m), KARST_SUCCESS);

  double fo[3];
  float *fx;
  long n = read_stl(stl, fo, &fx);
  assert_int_equal(n, m.n_triangles);
  for (int a = 0; a < 3; a++)
    assert_close(fo[a], o[a], 0);
  double worst = 0, worst_naive = 0;
  for (long i = 0; i < n; i++)
    for (int k = 0; k < 3; k++)
      for (int a = 0; a < 3; a++) {
        double x = m.xyz[3 * m.tri[3 * i + k] + a];
        worst = fmax(worst, fabs((double)fx[9 * i + 3 * k + a] + fo[a] - x));
        worst_naive = fmax(worst_naive, fabs((double)(float)x - x));
      }
  printf("STL at UTM coordinates: worst vertex error %.2g m with the origin, %.2g m without\n",
         worst, worst_naive);
  assert_true(worst < 1e-3);
  assert_int_equal(degenerate_float_triangles(fx, n, fo), 0);
  /* the same file without the origin: what the check above guards against */
  for (long i = 0; i < 9 * n; i++) {
    int a = (int)(i % 3);
    fx[i] = (float)((double)fx[i] + fo[a]);
  }
  const double zero[3] = {0, 0, 0};
  assert_true(worst_naive > 1e-3);
  assert_true(degenerate_float_triangles(fx, n, zero) > 0);
  free(fx);

  /* PLY: double coordinates, exact */
  FILE *f = fopen(ply, "rb");
  assert_non_null(f);
  char line[256];
  while (fgets(line, sizeof line, f) && strcmp(line, "end_header\n") != 0) {
  }
  for (karst_int_t i = 0; i < m.n_vertices; i++) {
    double xyz[3];
    assert_int_equal(fread(xyz, 8, 3, f), 3);
    for (int a = 0; a < 3; a++)
      assert_close(xyz[a], m.xyz[3 * i + a], 0);
  }
  fclose(f);

  /* a mesh near the origin keeps its coordinates: origin 0 */
  karst_mesh_t near;
  karst_mesh_init(&near);
  double nxyz[9] = {-999, 0, 0, 1000, 0, 0, 0, 1, 0};
  karst_int_t ntri[3] = {0, 1, 2};
  near.xyz = nxyz, near.tri = ntri, near.n_vertices = 3, near.n_triangles = 1;
  karst_mesh_stl_origin(&near, o);
  assert_close(o[0], 0, 0);
  nxyz[0] = -1000.5; /* beyond ±1000 m: rounded down to -1100 */
  karst_mesh_stl_origin(&near, o);
  assert_close(o[0], -1100, 0);
  assert_close(o[1], 0, 0);

  remove(stl);
  remove(ply);
  rmdir(dir);
  karst_mesh_destroy(&m);
  karst_sdf_free(t);
}

/* Bad arguments are errors naming the value; the output mesh is left empty. */
static void test_errors(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  karst_sdf_t *t;
  karst_sdf_create(&ctx, &t);
  karst_mesh_t m;
  karst_mesh_init(&m);
  double box[6] = {0, 0, 0, 1, 1, 1};
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, 0.1, &m, NULL), KARST_EINVAL);
  assert_non_null(strstr(ctx.errmsg, "no root"));
  double c[3] = {0, 0, 0};
  karst_int_t id;
  karst_sdf_sphere(&ctx, t, c, 0.4, 0, &id);
  karst_sdf_set_root(&ctx, t, id);
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, 0, &m, NULL), KARST_EINVAL);
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, 0.6, &m, NULL), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "two voxels"));
  double inv[6] = {0, 0, 0, -1, 1, 1};
  assert_int_equal(karst_mesh_polygonize(&ctx, t, inv, 0.1, &m, NULL), KARST_EINVAL);
  double huge[6] = {0, 0, 0, 1e6, 1e6, 1e6};
  assert_int_equal(karst_mesh_polygonize(&ctx, t, huge, 1e-3, &m, NULL), KARST_ERANGE);
  assert_int_equal(m.n_triangles, 0);
  /* interruption */
  volatile int stop = 1;
  ctx.interrupt = &stop;
  assert_int_equal(karst_mesh_polygonize(&ctx, t, box, 0.05, &m, NULL), KARST_EINTERRUPTED);
  assert_int_equal(m.n_triangles, 0);
  ctx.interrupt = NULL;
  /* sampling: the value at a grid point is the clipped field there */
  int dims[3];
  double origin[3];
  float *v = NULL;
  double sbox[6] = {-1, -1, -1, 1, 1, 1};
  assert_int_equal(karst_mesh_sample(&ctx, t, sbox, 0.5, dims, origin, &v), KARST_SUCCESS);
  assert_int_equal(dims[0], 5);
  assert_close(v[(2 * 5 + 2) * 5 + 2], -0.4, 1e-7); /* centre of the sphere */
  assert_close(v[0], sqrt(3.0) - 0.4,
               1e-6); /* corner: the sphere's value beats the clip box's 0.43 */
  free(v);
  /* the grid without the field: ceil(length / voxel) cells, by hand; sampling
   * past 2^28 points is refused before any evaluation, naming the cells */
  karst_int_t cells[3];
  double big[6] = {0, 0, 0, 100, 100, 30};
  assert_int_equal(karst_mesh_grid(&ctx, big, 0.1, cells), KARST_SUCCESS);
  assert_int_equal(cells[0], 1000);
  assert_int_equal(cells[1], 1000);
  assert_int_equal(cells[2], 300);
  assert_int_equal(karst_mesh_grid(&ctx, big, 0.3, cells), KARST_SUCCESS);
  assert_int_equal(cells[0], 334);
  assert_int_equal(karst_mesh_grid(&ctx, big, 20, cells), KARST_ERANGE);
  v = NULL;
  assert_int_equal(karst_mesh_sample(&ctx, t, big, 0.1, dims, origin, &v), KARST_ERANGE);
  assert_non_null(strstr(ctx.errmsg, "1000 x 1000 x 300 cells (301602301 points"));
  assert_null(v);
  karst_sdf_free(t);
}

/* Names in directory @p dir other than "." and "..", counted. */
static int count_entries(const char *dir) {
  DIR *d = opendir(dir);
  assert_non_null(d);
  int n = 0;
  struct dirent *e;
  while ((e = readdir(d)))
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) n++;
  closedir(d);
  return n;
}

static void write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

/* What karst mesh does with its outputs (karst/io.h): each path is checked
 * before any work (nothing is left behind by the check), its temporary keeps
 * the extension, and the set is committed together: when the second rename
 * fails (its target became a directory after the check), the first output
 * is put back to its previous version and no temporary remains. */
static void test_output_checks(void **state) {
  (void)state;
  karst_ctx_t ctx;
  karst_ctx_init(&ctx);
  char dir[] = "/tmp/karst_outset_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char a[256], b[256], missing[256], file_as_dir[300];
  snprintf(a, sizeof a, "%s/cave.ply", dir);
  snprintf(b, sizeof b, "%s/cave.vti", dir);
  snprintf(missing, sizeof missing, "%s/nodir/cave.vti", dir);
  snprintf(file_as_dir, sizeof file_as_dir, "%s/x.ply", a);

  assert_int_equal(karst_check_writable(&ctx, a), KARST_SUCCESS);
  assert_int_equal(count_entries(dir), 0);
  assert_int_equal(karst_check_writable(&ctx, missing), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "nodir' does not exist"));
  assert_int_equal(karst_check_writable(&ctx, dir), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "is a directory"));
  assert_int_equal(karst_check_writable(&ctx, ""), KARST_EINVAL);
  write_text(a, "old mesh\n");
  assert_int_equal(karst_check_writable(&ctx, file_as_dir), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "is not a directory"));

  char *ta = karst_temp_name_ext(a), *tb = karst_temp_name_ext(b);
  assert_non_null(ta);
  assert_non_null(tb);
  assert_string_equal(ta + strlen(ta) - 4, ".ply");
  assert_string_equal(tb + strlen(tb) - 4, ".vti");
  assert_ptr_equal(strstr(ta, dir), ta); /* beside the target */

  karst_fileset_t fs;
  karst_fileset_init(&fs);
  const char *wa, *wb;
  assert_int_equal(karst_fileset_add(&ctx, &fs, a, ta, &wa), KARST_SUCCESS);
  assert_int_equal(karst_fileset_add(&ctx, &fs, b, tb, &wb), KARST_SUCCESS);
  write_text(wa, "new mesh\n");
  write_text(wb, "field\n");
  char sub[300];
  snprintf(sub, sizeof sub, "%s/x", b);
  assert_int_equal(mkdir(b, 0777), 0);
  write_text(sub, "x\n"); /* a non-empty directory: rename onto it fails */
  assert_int_equal(karst_fileset_commit(&ctx, &fs), KARST_EIO);
  assert_non_null(strstr(ctx.errmsg, "cave.vti"));
  karst_fileset_abort(&fs);
  FILE *f = fopen(a, "r");
  assert_non_null(f);
  char line[64] = "";
  assert_non_null(fgets(line, sizeof line, f));
  fclose(f);
  assert_string_equal(line, "old mesh\n");
  assert_int_equal(count_entries(dir), 2); /* the old mesh and the directory in the way */
  free(ta);
  free(tb);
  remove(sub);
  rmdir(b);
  remove(a);
  rmdir(dir);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_tube_volume),
      cmocka_unit_test(test_sphere_volume),
      cmocka_unit_test(test_clip_closed),
      cmocka_unit_test(test_deterministic),
      cmocka_unit_test(test_skipping),
      cmocka_unit_test(test_network_mesh),
      cmocka_unit_test(test_writers),
      cmocka_unit_test(test_errors),
      cmocka_unit_test(test_no_collapsed_triangles),
      cmocka_unit_test(test_far_from_origin),
      cmocka_unit_test(test_output_checks),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
