#pragma once
// Materials built in code for renderer tests.

#include <cmath>
#include <memory>
#include <numbers>
#include <random>

#include "hapticlab/renderer/ar.hpp"
#include "hapticlab/renderer/material.hpp"
#include "hapticlab/renderer/neural.hpp"

namespace hapticlab::test {

// A 3 x 3 grid bank of AR(order) models with distinct resonances per cell.
inline renderer::VibrationBank GridBank(int order = 6) {
  renderer::VibrationBank b;
  b.sample_rate_hz = 2000;
  b.grid_speeds_mps = {0.04, 0.08, 0.12};
  b.grid_forces_N = {0.54, 1.18, 1.91};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      // LSFs spread evenly, shifted per cell: always a valid, stable model.
      renderer::ArCell c;
      c.speed_mps = b.grid_speeds_mps[static_cast<std::size_t>(i)];
      c.force_N = b.grid_forces_N[static_cast<std::size_t>(j)];
      for (int k = 0; k < order; ++k)
        c.lsf.push_back((k + 0.6 + 0.1 * i + 0.05 * j) * 3.0 / (order + 1));
      c.coeffs = renderer::LsfToAr(c.lsf);
      c.variance = 0.5 + i + 0.5 * j;
      b.cells.push_back(c);
    }
  }
  return b;
}

inline renderer::MaterialModel TexturedMaterial() {
  renderer::MaterialModel m;
  m.name = "test";
  m.contact.texture = {800, 2, 1.2};
  m.contact.base = {1500, 0, 1};
  m.contact.layer_thickness_m = 0.5e-3;
  m.friction = {2500, 0.35, 0.4};
  // A rough random height map, 256 x 256 at 20 µm, heights up to 40 µm.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> u(0.f, 40e-6f);
  std::vector<float> h(256 * 256);
  for (auto& x : h) x = u(rng);
  m.geometry = std::make_shared<renderer::HeightMap>(256, 256, 20e-6, h);
  m.vibration = GridBank();
  m.hybrid_cutoff_hz = 100;
  return m;
}

// TexturedMaterial with a Γ_U neural vibration model whose linear part is one AR(2) resonance
// at 200 Hz with pole radius `radius` everywhere (the network's own output is zero): stable
// below 1, a runaway above (the issue-#33 case of a model that was kept unstable).
inline renderer::MaterialModel NeuralResonanceMaterial(double radius) {
  auto nm = std::make_shared<renderer::NeuralModel>();
  nm->topology = renderer::NeuralTopology::kUnified;
  nm->sample_rate_hz = 2000;
  nm->min_speed_mps = 0.01;
  nm->speeds_mps = {0.02, 0.1};
  nm->forces_N = {0.1, 3.0};
  renderer::NeuralBand b;
  b.lo_hz = 20;
  b.hi_hz = 900;
  b.decimation = 1;
  b.history = 2;
  b.scale = 1;
  renderer::NeuralNet n;
  n.layers = {4, 1};
  n.params.assign(5, 0.0);
  n.linear.assign(renderer::kNeuralLinearTerms * 2, 0.0);
  n.linear[0] = 2 * radius * std::cos(2 * std::numbers::pi * 200 / 2000);  // constant term
  n.linear[1] = -radius * radius;
  b.nets = {n};
  b.sigma.assign(4, 0.1);
  nm->bands = {b};
  auto m = TexturedMaterial();
  m.neural = nm;
  return m;
}

}  // namespace hapticlab::test
