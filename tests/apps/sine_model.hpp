#pragma once
// A small material model (sine geometry, Coulomb + Dahl friction, one AR cell) for the CLI
// tests that need a model file.

namespace hapticlab::test {

inline constexpr const char* kSineModelToml = R"(name = "Sine test"
effects = ["coulomb", "dahl"]
[contact]
texture_K = 900.0
base_K = 2000.0
layer_thickness_m = 5e-4
[friction]
kappa_N_per_m = 2000.0
mu_k = 0.3
[geometry]
kind = "sine"
amplitude_m = 1e-5
wavelength_m = 1e-3
[hybrid]
cutoff_hz = 100
[vibration]
sample_rate_hz = 2000
[[vibration.cells]]
speed_mps = 0.05
force_N = 1.0
ar = [0.5, -0.3]
variance = 0.2
)";

}  // namespace hapticlab::test
