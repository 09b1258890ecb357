// The one CGAL translation unit (CGAL 5.5): an independent check of a
// triangle mesh with CGAL::Polygon_mesh_processing, used by the tests of
// src/mesh/, and the convex hulls and half-space intersections of the rock
// blocks (src/blocks/, Paris et al. 2020 §4.2). Thin extern "C" shim, no
// algorithm of ours lives here.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Random.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Triangulation_3.h>
#include <CGAL/boost/graph/helpers.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iterator>
#include <map>
#include <vector>

#include "geometry/geometry_internal.h"
#include "mesh/mesh_internal.h"

namespace PMP = CGAL::Polygon_mesh_processing;
typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Surface_mesh<K::Point_3> Mesh;

extern "C" int karst_i_cgal_check_mesh(const double *xyz, karst_int_t n_vertices,
                                       const karst_int_t *tri, karst_int_t n_triangles,
                                       karst_i_cgal_report_t *rep, char *err, size_t errlen) {
  try {
    *rep = karst_i_cgal_report_t{0, 0, 0, 0.0};
    std::vector<K::Point_3> pts;
    pts.reserve(static_cast<size_t>(n_vertices));
    for (karst_int_t i = 0; i < n_vertices; i++)
      pts.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    std::vector<std::array<std::size_t, 3>> polys(static_cast<size_t>(n_triangles));
    for (karst_int_t i = 0; i < n_triangles; i++)
      for (int k = 0; k < 3; k++)
        polys[i][k] = static_cast<std::size_t>(tri[3 * i + k]);
    rep->is_polygon_mesh = PMP::is_polygon_soup_a_polygon_mesh(polys) ? 1 : 0;
    if (!rep->is_polygon_mesh || n_triangles == 0) return 0;
    Mesh m;
    PMP::polygon_soup_to_polygon_mesh(pts, polys, m);
    rep->closed = CGAL::is_closed(m) ? 1 : 0;
    if (rep->closed) {
      rep->outward = PMP::is_outward_oriented(m) ? 1 : 0;
      rep->volume = CGAL::to_double(PMP::volume(m));
    }
    return 0;
  } catch (const std::exception &e) {
    if (err && errlen) std::snprintf(err, errlen, "CGAL: %s", e.what());
    return -1;
  } catch (...) {
    if (err && errlen) std::snprintf(err, errlen, "CGAL: unknown exception");
    return -1;
  }
}

extern "C" void karst_i_polytope_destroy(karst_i_polytope_t *p) {
  if (!p) return;
  std::free(p->xyz);
  std::free(p->tri);
  std::free(p->planes);
  *p = karst_i_polytope_t{0, 0, 0, nullptr, nullptr, nullptr, 0.0};
}

/* CGAL's hulls draw from the thread's default random generator: reseed it
 * before every call so that a block depends on its points only, not on the
 * thread or the blocks computed before it (byte-identical outputs). */
static void reseed() {
  CGAL::get_default_random() = CGAL::Random(0);
}

/* The convex hull of points spanning a volume as a triangle mesh oriented
 * outward, from the facets of a 3-D triangulation incident to its infinite
 * vertex. (CGAL 5.5's convex_hull_3 quickhull erases a list node twice when
 * the farthest point of its first plane is one of that plane's points, a
 * use-after-free valgrind shows on block hulls; the triangulation has no
 * such path.) Returns false when the points do not span a volume. */
static bool hull_mesh(const std::vector<K::Point_3> &pts, Mesh &out) {
  typedef CGAL::Triangulation_3<K> T3;
  T3 t(pts.begin(), pts.end());
  if (t.dimension() < 3) return false;
  double c[3] = {0, 0, 0};
  for (const auto &p : pts)
    c[0] += p.x() / pts.size(), c[1] += p.y() / pts.size(), c[2] += p.z() / pts.size();
  std::vector<K::Point_3> vp;
  std::vector<std::array<std::size_t, 3>> tris;
  std::map<T3::Vertex_handle, std::size_t> id;
  std::vector<T3::Cell_handle> cells;
  t.incident_cells(t.infinite_vertex(), std::back_inserter(cells));
  for (T3::Cell_handle ch : cells) {
    int inf = ch->index(t.infinite_vertex());
    std::array<std::size_t, 3> tri;
    for (int k = 0; k < 3; k++) {
      T3::Vertex_handle v = ch->vertex(T3::vertex_triple_index(inf, k));
      auto it = id.find(v);
      if (it == id.end()) {
        it = id.emplace(v, vp.size()).first;
        vp.push_back(v->point());
      }
      tri[k] = it->second;
    }
    K::Vector_3 n = CGAL::cross_product(vp[tri[1]] - vp[tri[0]], vp[tri[2]] - vp[tri[0]]);
    double o = n.x() * (vp[tri[0]].x() - c[0]) + n.y() * (vp[tri[0]].y() - c[1]) +
               n.z() * (vp[tri[0]].z() - c[2]);
    if (o < 0) std::swap(tri[1], tri[2]);
    tris.push_back(tri);
  }
  /* deterministic order: by vertex triple (the triangulation's cell order follows its memory) */
  std::sort(tris.begin(), tris.end(),
            [&](const std::array<std::size_t, 3> &a, const std::array<std::size_t, 3> &b) {
              for (int k = 0; k < 3; k++) {
                const K::Point_3 &p = vp[a[k]], &q = vp[b[k]];
                if (p != q) return p < q;
              }
              return false;
            });
  if (!PMP::is_polygon_soup_a_polygon_mesh(tris)) return false;
  PMP::polygon_soup_to_polygon_mesh(vp, tris, out);
  return true;
}

static void say(char *err, size_t errlen, const char *what) {
  if (err && errlen) std::snprintf(err, errlen, "CGAL: %s", what);
}

extern "C" int karst_i_cgal_hull_planes(const double *xyz, karst_int_t n, double **planes,
                                        karst_int_t *n_planes, char *err, size_t errlen) {
  *planes = nullptr;
  *n_planes = 0;
  reseed();
  try {
    std::vector<K::Point_3> pts;
    pts.reserve(static_cast<size_t>(n));
    for (karst_int_t i = 0; i < n; i++)
      pts.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    Mesh hull;
    if (!hull_mesh(pts, hull)) {
      say(err, errlen, "the points do not span a volume");
      return -1;
    }
    size_t nf = hull.number_of_faces();
    double *out = static_cast<double *>(std::malloc((nf ? nf : 1) * 4 * sizeof(double)));
    if (!out) {
      say(err, errlen, "out of memory for the hull planes");
      return -1;
    }
    karst_int_t k = 0;
    for (Mesh::Face_index f : hull.faces()) {
      std::array<K::Point_3, 3> v;
      int c = 0;
      for (Mesh::Vertex_index w : CGAL::vertices_around_face(hull.halfedge(f), hull))
        if (c < 3) v[c++] = hull.point(w);
      if (c != 3) continue;
      K::Vector_3 nrm = CGAL::cross_product(v[1] - v[0], v[2] - v[0]);
      double l = std::sqrt(CGAL::to_double(nrm.squared_length()));
      if (!(l > 0)) continue; /* a zero-area hull triangle has no plane */
      double u[3] = {nrm.x() / l, nrm.y() / l, nrm.z() / l};
      out[4 * k] = u[0], out[4 * k + 1] = u[1], out[4 * k + 2] = u[2];
      out[4 * k + 3] = u[0] * v[0].x() + u[1] * v[0].y() + u[2] * v[0].z();
      k++;
    }
    *planes = out;
    *n_planes = k;
    return 0;
  } catch (const std::exception &e) {
    say(err, errlen, e.what());
  } catch (...) {
    say(err, errlen, "unknown exception");
  }
  std::free(*planes);
  *planes = nullptr;
  return -1;
}

extern "C" int karst_i_cgal_halfspaces(const double *planes, karst_int_t m,
                                       const double interior[3], double tol,
                                       karst_i_polytope_t *out, char *err, size_t errlen) {
  /* By polar duality about the interior point c: the half-space u.p <= d
   * becomes the point u / (d - u.c); the convex hull of those points
   * (CGAL::convex_hull_3 with the ordinary traits) has one vertex per face of
   * the polytope and one face per vertex: the primal vertex of a dual face
   * with normal n through dual point q is c + n / (n.q). (CGAL's
   * halfspace_intersection_3 was not used: its dual-traits quickhull reads
   * freed memory on near-duplicate planes, seen with valgrind.) */
  *out = karst_i_polytope_t{0, 0, 0, nullptr, nullptr, nullptr, 0.0};
  reseed();
  try {
    const double *c = interior;
    std::vector<K::Point_3> dual;
    std::vector<karst_int_t> plane_of;
    dual.reserve(static_cast<size_t>(m));
    for (karst_int_t i = 0; i < m; i++) {
      const double *u = planes + 4 * i;
      double h = u[3] - (u[0] * c[0] + u[1] * c[1] + u[2] * c[2]);
      if (!(h > 0)) {
        say(err, errlen, "the interior point is not strictly inside every half-space");
        return -1;
      }
      dual.emplace_back(u[0] / h, u[1] / h, u[2] / h);
      plane_of.push_back(i);
    }
    Mesh H;
    if (!hull_mesh(dual, H) || H.number_of_faces() < 4) {
      say(err, errlen, "the half-spaces do not bound a polytope");
      return -1;
    }
    /* primal vertices: one per dual face, merged when within tol */
    std::vector<std::array<double, 3>> pv;
    std::vector<karst_int_t> vid(H.num_faces(), -1);
    for (Mesh::Face_index f : H.faces()) {
      std::array<K::Point_3, 3> q;
      int k = 0;
      for (Mesh::Vertex_index w : CGAL::vertices_around_face(H.halfedge(f), H))
        if (k < 3) q[k++] = H.point(w);
      K::Vector_3 n = CGAL::cross_product(q[1] - q[0], q[2] - q[0]);
      double nq = n.x() * q[0].x() + n.y() * q[0].y() + n.z() * q[0].z();
      if (!(nq > 0)) {
        say(err, errlen, "the polytope is unbounded (the interior point lies on its dual hull)");
        return -1;
      }
      std::array<double, 3> x = {c[0] + n.x() / nq, c[1] + n.y() / nq, c[2] + n.z() / nq};
      karst_int_t found = -1;
      for (size_t j = 0; j < pv.size() && found < 0; j++)
        if (std::fabs(pv[j][0] - x[0]) <= tol && std::fabs(pv[j][1] - x[1]) <= tol &&
            std::fabs(pv[j][2] - x[2]) <= tol)
          found = static_cast<karst_int_t>(j);
      if (found < 0) {
        found = static_cast<karst_int_t>(pv.size());
        pv.push_back(x);
      }
      vid[f] = found;
    }
    /* primal faces: around each dual vertex, its faces in order (outward:
     * the dual's orientation reverses, so the cycle is read backwards) */
    std::vector<std::vector<std::size_t>> polys;
    std::vector<karst_int_t> face_plane;
    std::vector<karst_int_t> dual_index(H.num_vertices(), -1);
    {
      /* which input plane each hull vertex is: match the points */
      size_t k = 0;
      for (Mesh::Vertex_index w : H.vertices()) {
        const K::Point_3 &p = H.point(w);
        for (size_t i = 0; i < dual.size(); i++)
          if (dual[i] == p) {
            dual_index[w] = plane_of[i];
            break;
          }
        k++;
      }
      (void)k;
    }
    for (Mesh::Vertex_index w : H.vertices()) {
      std::vector<std::size_t> poly;
      for (Mesh::Face_index f : CGAL::faces_around_target(H.halfedge(w), H)) {
        if (f == Mesh::null_face()) continue;
        std::size_t v = static_cast<std::size_t>(vid[f]);
        if (poly.empty() || (poly.back() != v && poly.front() != v)) poly.push_back(v);
      }
      if (poly.size() < 3) continue; /* a face shrunk to an edge or a point */
      /* outward: the Newell normal along the plane's normal */
      double nn[3] = {0, 0, 0};
      for (size_t k = 0; k < poly.size(); k++) {
        const auto &a = pv[poly[k]], &b = pv[poly[(k + 1) % poly.size()]];
        nn[0] += (a[1] - b[1]) * (a[2] + b[2]);
        nn[1] += (a[2] - b[2]) * (a[0] + b[0]);
        nn[2] += (a[0] - b[0]) * (a[1] + b[1]);
      }
      const double *u = planes + 4 * (dual_index[w] >= 0 ? dual_index[w] : 0);
      if (nn[0] * u[0] + nn[1] * u[1] + nn[2] * u[2] < 0) std::reverse(poly.begin(), poly.end());
      polys.push_back(poly);
      face_plane.push_back(dual_index[w]);
    }
    std::vector<K::Point_3> pts;
    for (const auto &x : pv)
      pts.emplace_back(x[0], x[1], x[2]);
    /* PMP::volume wants triangles: the faces are convex, fans will do */
    std::vector<std::array<std::size_t, 3>> fan;
    for (const auto &poly : polys)
      for (size_t k = 1; k + 1 < poly.size(); k++)
        fan.push_back({poly[0], poly[k], poly[k + 1]});
    if (!PMP::is_polygon_soup_a_polygon_mesh(fan)) {
      say(err, errlen, "the polytope's faces do not close");
      return -1;
    }
    Mesh P;
    PMP::polygon_soup_to_polygon_mesh(pts, fan, P);
    if (!CGAL::is_closed(P)) {
      say(err, errlen, "the intersection of the half-spaces is not a closed polytope");
      return -1;
    }
    out->volume = CGAL::to_double(PMP::volume(P));
    size_t nt = 0;
    for (const auto &poly : polys)
      nt += poly.size() - 2;
    out->xyz = static_cast<double *>(std::malloc(3 * (pv.size() ? pv.size() : 1) * sizeof(double)));
    out->tri = static_cast<karst_int_t *>(std::malloc(3 * (nt ? nt : 1) * sizeof(karst_int_t)));
    out->planes = static_cast<double *>(std::malloc(4 * (polys.size() + 1) * sizeof(double)));
    if (!out->xyz || !out->tri || !out->planes) {
      karst_i_polytope_destroy(out);
      say(err, errlen, "out of memory for the polytope");
      return -1;
    }
    for (size_t i = 0; i < pv.size(); i++)
      for (int a = 0; a < 3; a++)
        out->xyz[3 * i + a] = pv[i][a];
    out->n_vertices = static_cast<karst_int_t>(pv.size());
    karst_int_t t = 0;
    for (const auto &poly : polys) /* fans: the faces are convex */
      for (size_t k = 1; k + 1 < poly.size(); k++) {
        out->tri[3 * t] = static_cast<karst_int_t>(poly[0]);
        out->tri[3 * t + 1] = static_cast<karst_int_t>(poly[k]);
        out->tri[3 * t + 2] = static_cast<karst_int_t>(poly[k + 1]);
        t++;
      }
    out->n_triangles = t;
    /* the supporting planes, in input order */
    std::vector<char> used(static_cast<size_t>(m), 0);
    for (karst_int_t i : face_plane)
      if (i >= 0) used[static_cast<size_t>(i)] = 1;
    karst_int_t k = 0;
    for (karst_int_t i = 0; i < m; i++) {
      if (!used[static_cast<size_t>(i)]) continue;
      for (int a = 0; a < 4; a++)
        out->planes[4 * k + a] = planes[4 * i + a];
      k++;
    }
    out->n_planes = k;
    return 0;
  } catch (const std::exception &e) {
    say(err, errlen, e.what());
  } catch (...) {
    say(err, errlen, "unknown exception");
  }
  karst_i_polytope_destroy(out);
  return -1;
}
