// The one CGAL translation unit (CGAL 5.5): an independent check of a
// triangle mesh with CGAL::Polygon_mesh_processing, used by the tests of
// src/mesh/, and the convex hulls and half-space intersections of the rock
// blocks (src/blocks/, Paris et al. 2020 §4.2). Thin extern "C" shim, no
// algorithm of ours lives here.
#include <CGAL/Convex_hull_3/dual/halfspace_intersection_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>
#include <CGAL/convex_hull_3.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
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

static void say(char *err, size_t errlen, const char *what) {
  if (err && errlen) std::snprintf(err, errlen, "CGAL: %s", what);
}

extern "C" int karst_i_cgal_hull_planes(const double *xyz, karst_int_t n, double **planes,
                                        karst_int_t *n_planes, char *err, size_t errlen) {
  *planes = nullptr;
  *n_planes = 0;
  try {
    std::vector<K::Point_3> pts;
    pts.reserve(static_cast<size_t>(n));
    for (karst_int_t i = 0; i < n; i++)
      pts.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    Mesh hull;
    CGAL::convex_hull_3(pts.begin(), pts.end(), hull);
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
  *out = karst_i_polytope_t{0, 0, 0, nullptr, nullptr, nullptr, 0.0};
  try {
    std::vector<K::Plane_3> hs;
    hs.reserve(static_cast<size_t>(m));
    for (karst_int_t i = 0; i < m; i++) /* u.p - d <= 0 is the negative side */
      hs.emplace_back(planes[4 * i], planes[4 * i + 1], planes[4 * i + 2], -planes[4 * i + 3]);
    Mesh P;
    CGAL::halfspace_intersection_3(hs.begin(), hs.end(), P,
                                   K::Point_3(interior[0], interior[1], interior[2]));
    if (P.number_of_faces() == 0) {
      say(err, errlen, "the half-spaces intersect in nothing bounded");
      return -1;
    }
    PMP::triangulate_faces(P);
    if (!CGAL::is_closed(P)) {
      say(err, errlen, "the intersection of the half-spaces is not a closed polytope");
      return -1;
    }
    out->volume = CGAL::to_double(PMP::volume(P));
    size_t nv = P.number_of_vertices(), nt = P.number_of_faces();
    out->xyz = static_cast<double *>(std::malloc(3 * nv * sizeof(double)));
    out->tri = static_cast<karst_int_t *>(std::malloc(3 * nt * sizeof(karst_int_t)));
    out->planes = static_cast<double *>(std::malloc(4 * (m ? m : 1) * sizeof(double)));
    if (!out->xyz || !out->tri || !out->planes) {
      karst_i_polytope_destroy(out);
      say(err, errlen, "out of memory for the polytope");
      return -1;
    }
    std::vector<karst_int_t> id(P.num_vertices(), -1);
    karst_int_t k = 0;
    for (Mesh::Vertex_index v : P.vertices()) {
      const K::Point_3 &q = P.point(v);
      id[v] = k;
      out->xyz[3 * k] = q.x(), out->xyz[3 * k + 1] = q.y(), out->xyz[3 * k + 2] = q.z();
      k++;
    }
    out->n_vertices = k;
    k = 0;
    for (Mesh::Face_index f : P.faces()) {
      int c = 0;
      for (Mesh::Vertex_index w : CGAL::vertices_around_face(P.halfedge(f), P))
        if (c < 3) out->tri[3 * k + c++] = id[w];
      if (c == 3) k++;
    }
    out->n_triangles = k;
    k = 0;
    for (karst_int_t i = 0; i < m; i++) {
      int on = 0;
      for (karst_int_t v = 0; v < out->n_vertices && on < 3; v++) {
        const double *q = out->xyz + 3 * v;
        double h = planes[4 * i] * q[0] + planes[4 * i + 1] * q[1] + planes[4 * i + 2] * q[2] -
                   planes[4 * i + 3];
        if (std::fabs(h) <= tol) on++;
      }
      if (on < 3) continue;
      for (int c = 0; c < 4; c++)
        out->planes[4 * k + c] = planes[4 * i + c];
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
