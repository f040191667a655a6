#pragma once
/// @file Delaunay triangulation of scattered (speed, force) model points, through Qhull
/// (a maintained library; we do not hand-write computational geometry).

#include <array>
#include <vector>

namespace hapticlab::renderer {

/// Triangulates points (x_i, y_i). Each axis is first scaled by its range, so speeds in m/s
/// and forces in N weigh alike (Delaunay triangulations are not affine invariant; this is
/// the same choice as triangulating in normalised units). Returns 0-based index triples.
/// @throws PreconditionError for fewer than 3 points or points on an axis-parallel line
/// (callers with user data check first); std::runtime_error with Qhull's message when the
/// triangulation fails.
std::vector<std::array<int, 3>> DelaunayTriangulate(const std::vector<double>& x,
                                                    const std::vector<double>& y);

}  // namespace hapticlab::renderer
