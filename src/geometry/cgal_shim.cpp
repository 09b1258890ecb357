// The one CGAL translation unit (CGAL 5.5): an independent check of a
// triangle mesh with CGAL::Polygon_mesh_processing, used by the tests of
// src/mesh/. Thin extern "C" shim, no algorithm of ours lives here.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <array>
#include <cstdio>
#include <exception>
#include <vector>

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
