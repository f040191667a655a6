#pragma once
/// @file Heights from surface normals (dissertation ch. IV.2, the last step of photometric
/// stereo): Frankot-Chellappa (FFT, periodic boundary), a Poisson solve with Neumann boundary
/// on the image edge (DCT) and the same on an irregular mask (sparse Cholesky). FFTW and
/// Eigen do the transforms and the factorisation.
///
/// **Image frame**: x along the image columns (to the right), y along the image rows
/// (downwards), z up out of the sample; normals are unit vectors in that frame, row-major,
/// width x height of them. Heights come back in metres (pixel pitch `pitch_m` [m]).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace hapticlab::modeling {

/// How normals become heights.
enum class Integration {
  kFrankotChellappa,  ///< FFT, periodic boundary (best for textures that tile); whole image only
  kPoisson,  ///< Poisson solve, Neumann boundary on the image edge (DCT) or on the mask boundary
             ///< (sparse)
};

/// Frankot-Chellappa: the height whose gradient is closest (least squares, periodic
/// boundary) to (p, q) = (dh/dx, dh/dy) in height units per pixel; scaled by pitch_m.
std::vector<float> IntegrateNormals(const std::vector<Eigen::Vector3f>& normals, int width,
                                    int height, double pitch_m);
/// The least-squares height whose differences between 4-neighbours match the normals'
/// gradients (averaged over each pair), i.e. a Poisson solve with Neumann boundary on the
/// image edge (DCT, FFTW); zero mean; scaled by pitch_m.
std::vector<float> IntegrateNormalsPoisson(const std::vector<Eigen::Vector3f>& normals, int width,
                                           int height, double pitch_m);
/// The same on an irregular domain: only pairs of neighbours both inside `mask` (non-zero)
/// count, so the boundary condition is Neumann on the mask boundary (sparse Cholesky, Eigen).
/// Each connected region has zero mean; outside pixels get the lowest inside height.
std::vector<float> IntegrateNormalsMasked(const std::vector<Eigen::Vector3f>& normals,
                                          const std::vector<std::uint8_t>& mask, int width,
                                          int height, double pitch_m);

}  // namespace hapticlab::modeling
