#include "hapticlab/renderer/delaunay.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

extern "C" {
#include <libqhull_r/qhull_ra.h>

#include "hapticlab/core/status.hpp"
}

namespace hapticlab::renderer {

std::vector<std::array<int, 3>> DelaunayTriangulate(const std::vector<double>& x,
                                                    const std::vector<double>& y) {
  HL_REQUIRE(x.size() == y.size(), "Delaunay: x and y differ in length");
  const int n = static_cast<int>(x.size());
  HL_REQUIRE(n >= 3, "Delaunay: at least 3 points are needed, got " + std::to_string(n));
  const auto [xmin, xmax] = std::minmax_element(x.begin(), x.end());
  const auto [ymin, ymax] = std::minmax_element(y.begin(), y.end());
  const double sx = *xmax - *xmin, sy = *ymax - *ymin;
  HL_REQUIRE(sx > 0 && sy > 0, "Delaunay: points are collinear (one axis has no spread)");
  std::vector<coordT> pts(2 * x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    pts[2 * i] = (x[i] - *xmin) / sx;
    pts[2 * i + 1] = (y[i] - *ymin) / sy;
  }
  // Qhull reports errors on a FILE*; capture them in memory for the exception message.
  char* err_buf = nullptr;
  std::size_t err_len = 0;
  FILE* err = open_memstream(&err_buf, &err_len);
  qhT qh_storage;
  qhT* qh = &qh_storage;
  qh_zero(qh, err);
  char flags[] = "qhull d Qt Qbb Qz";
  const int code = qh_new_qhull(qh, 2, n, pts.data(), False, flags, nullptr, err);
  std::vector<std::array<int, 3>> tris;
  if (code == 0) {
    facetT* facet;
    vertexT *vertex, **vertexp;
    FORALLfacets {
      if (facet->upperdelaunay) continue;
      std::array<int, 3> t{};
      int k = 0;
      FOREACHvertex_(facet->vertices) {
        if (k < 3) t[static_cast<std::size_t>(k)] = qh_pointid(qh, vertex->point);
        ++k;
      }
      if (k == 3) tris.push_back(t);
    }
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong, totlong;
  qh_memfreeshort(qh, &curlong, &totlong);
  std::fclose(err);
  const std::string message = err_buf ? std::string(err_buf, err_len) : std::string();
  std::free(err_buf);
  if (code != 0 || tris.empty())
    throw std::runtime_error("Delaunay triangulation failed: " +
                             (message.empty() ? "no triangles" : message));
  return tris;
}

}  // namespace hapticlab::renderer
