// The material model file's declared field tables (core/fields.hpp) and the key tables of
// docs/formats.md printed from them. The ranges are physical: generous for any real sample,
// but a typo of 1e100 never reaches the force loop.

#include "material_fields.hpp"

#include <string>

#include "hapticlab/renderer/material_keys.hpp"

namespace hapticlab::renderer {
namespace internal {
namespace {

using fields::Field;
using fields::Type;
template <class S>
using Fields = std::span<const Field<S>>;

constexpr fields::Range kStiffness = fields::OpenClosed(0, 1e12);
constexpr fields::Range kDamping{0, 1e12};
constexpr fields::Range kExponent{1, 2};
constexpr fields::Range kSpeed{0, 100};
constexpr fields::Range kForce{0, 1e3};

}  // namespace

Fields<MaterialModel> TopLevelFields() {
  static const Field<MaterialModel> kFields[] = {
      {.key = "name",
       .type = Type::kString,
       .ref = HL_FIELD_REF(MaterialModel, name),
       .required = true,
       .doc = "the material's name"},
      {.key = "effects",
       .type = Type::kStrings,
       .ref = HL_FIELD_REF(MaterialModel, effects),
       .doc = "named effects of the workbench catalogue",
       .default_text = "[]"},
      {.key = "contact",
       .type = Type::kCustom,
       .required = true,
       .doc = "[contact] below",
       .expected = "a table"},
      {.key = "friction",
       .type = Type::kCustom,
       .required = true,
       .doc = "[friction] below",
       .expected = "a table"},
      {.key = "geometry",
       .type = Type::kCustom,
       .doc = "[geometry] below",
       .default_text = "flat",
       .expected = "a table"},
      {.key = "vibration",
       .type = Type::kCustom,
       .doc = "[vibration] below",
       .default_text = "none",
       .expected = "a table"},
      {.key = "hybrid",
       .type = Type::kCustom,
       .doc = "[hybrid] below",
       .default_text = "cutoff_hz = 100",
       .expected = "a table"},
      {.key = "neural",
       .type = Type::kCustom,
       .doc = "[neural] below",
       .default_text = "none",
       .expected = "a table"},
      {.key = "notes", .type = Type::kCustom, .doc = "free, not read", .expected = "anything"},
      {.key = "workbench", .type = Type::kCustom, .doc = "free, not read", .expected = "anything"},
  };
  return kFields;
}

Fields<ContactParams> ContactFields() {
  static const Field<ContactParams> kFields[] = {
      {.key = "texture_K",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(ContactParams, texture.K),
       .range = kStiffness,
       .unit = "N/m^n",
       .required = true,
       .doc = "texture layer's Hunt-Crossley stiffness"},
      {.key = "texture_B",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(ContactParams, texture.B),
       .range = kDamping,
       .unit = "N s/m^(n+1)",
       .doc = "texture layer's damping"},
      {.key = "texture_n",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(ContactParams, texture.n),
       .range = kExponent,
       .doc = "texture layer's exponent"},
      {.key = "base_model",
       .type = Type::kChoice,
       .ref = +[](ContactParams& c, std::size_t i) { c.base_model = static_cast<BaseModel>(i); },
       .doc = "how the base under the layer pushes back",
       .choices = "linear|hunt-crossley",
       .chosen = +[](const ContactParams& c) { return static_cast<std::size_t>(c.base_model); }},
      {.key = "base_K",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(ContactParams, base.K),
       .range = {0, 1e12},
       .unit = "N/m^n",
       .doc = "base stiffness (0: half the device's maximum)"},
      {.key = "base_B",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(ContactParams, base.B),
       .range = kDamping,
       .unit = "N s/m^(n+1)",
       .doc = "base damping"},
      {.key = "base_n",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(ContactParams, base.n),
       .range = kExponent,
       .doc = "base exponent"},
      {.key = "layer_thickness_m",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(ContactParams, layer_thickness_m),
       .range = {0, 0.1},
       .unit = "m",
       .doc = "uniform layer under the height map's lowest point"},
  };
  return kFields;
}

Fields<FrictionParams> FrictionFields() {
  static const Field<FrictionParams> kFields[] = {
      {.key = "kappa_N_per_m",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(FrictionParams, kappa_N_per_m),
       .range = fields::OpenClosed(0, 1e9),
       .unit = "N/m",
       .required = true,
       .doc = "Dahl pre-sliding stiffness"},
      {.key = "mu_k",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(FrictionParams, mu_k),
       .range = {0, 10},
       .required = true,
       .doc = "Coulomb coefficient"},
      {.key = "mu_b_Ns_per_m",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(FrictionParams, mu_b_Ns_per_m),
       .range = {0, 1e4},
       .unit = "N s/m",
       .doc = "viscous coefficient"},
  };
  return kFields;
}

Fields<MaterialModel> GeometryFields() {
  static const Field<MaterialModel> kFields[] = {
      {.key = "kind",
       .type = Type::kCustom,
       .doc = "the height map's source",
       .default_text = "\"file\" when file is given, else \"flat\"",
       .expected = "file, sine or flat"},
      {.key = "file",
       .type = Type::kCustom,
       .unit = "",
       .doc = "kind = file: raw little-endian float32 heights [m], row-major, relative to the "
              "model",
       .expected = "a file name"},
      {.key = "width",
       .type = Type::kCustom,
       .doc = "kind = file: samples per row",
       .expected = "an integer 1..1048576"},
      {.key = "height",
       .type = Type::kCustom,
       .doc = "kind = file: rows",
       .expected = "an integer 1..1048576"},
      {.key = "pitch_m",
       .type = Type::kCustom,
       .unit = "m",
       .doc = "kind = file: sample spacing",
       .expected = "a number in (0, 0.01]"},
      {.key = "amplitude_m",
       .type = Type::kCustom,
       .unit = "m",
       .doc = "kind = sine: amplitude",
       .expected = "a number in [0, 0.01]"},
      {.key = "wavelength_m",
       .type = Type::kCustom,
       .unit = "m",
       .doc = "kind = sine: wavelength",
       .expected = "a number in (0, 1]"},
  };
  return kFields;
}

Fields<MaterialModel> HybridFields() {
  static const Field<MaterialModel> kFields[] = {
      {.key = "cutoff_hz",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(MaterialModel, hybrid_cutoff_hz),
       .range = {0, 1e5},
       .unit = "Hz",
       .required = true,
       .doc = "hybrid filter's f_c (0: no split)"},
  };
  return kFields;
}

Fields<MaterialModel> NeuralFields() {
  static const Field<MaterialModel> kFields[] = {
      {.key = "file",
       .type = Type::kString,
       .ref = HL_FIELD_REF(MaterialModel, neural_file),
       .required = true,
       .doc = "neural vibration model, relative to the model file"},
  };
  return kFields;
}

Fields<VibrationBank> VibrationFields() {
  static const Field<VibrationBank> kFields[] = {
      {.key = "file",
       .type = Type::kCustom,
       .doc = "a bank file holding this table (then no other key)",
       .default_text = "none",
       .expected = "a file name"},
      {.key = "sample_rate_hz",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(VibrationBank, sample_rate_hz),
       .range = fields::OpenClosed(0, 1e6),
       .unit = "Hz",
       .required = true,
       .doc = "rate the AR models run at"},
      {.key = "min_speed_mps",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(VibrationBank, min_speed_mps),
       .range = kSpeed,
       .unit = "m/s",
       .doc = "synthesis is off below this speed"},
      {.key = "max_speed_mps",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(VibrationBank, max_speed_mps),
       .range = kSpeed,
       .unit = "m/s",
       .doc = "modelled range: faster saturates (0: none; else > 1e-5)"},
      {.key = "max_force_N",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(VibrationBank, max_force_N),
       .range = kForce,
       .unit = "N",
       .doc = "modelled range: harder saturates (0: none; else > 0.01)"},
      {.key = "light_force_N",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(VibrationBank, light_force_N),
       .range = kForce,
       .unit = "N",
       .doc = "lighter loads are interpolated at 1e-4 N (0: off)"},
      {.key = "speeds_mps",
       .type = Type::kNumbers,
       .ref = HL_FIELD_REF(VibrationBank, grid_speeds_mps),
       .range = kSpeed,
       .unit = "m/s",
       .doc = "grid: ascending speeds",
       .default_text = "none (scattered cells)"},
      {.key = "forces_N",
       .type = Type::kNumbers,
       .ref = HL_FIELD_REF(VibrationBank, grid_forces_N),
       .range = kForce,
       .unit = "N",
       .doc = "grid: ascending forces (cells row-major, force fastest)",
       .default_text = "none (scattered cells)"},
      {.key = "cells",
       .type = Type::kCustom,
       .required = true,
       .doc = "the AR models, [[vibration.cells]] (below)",
       .expected = "an array of tables"},
      {.key = "triangles",
       .type = Type::kCustom,
       .doc = "scattered cells: their triangulation",
       .default_text = "Delaunay",
       .expected = "an array of [i, j, k] cell indices"},
  };
  return kFields;
}

Fields<ArCell> CellFields() {
  static const Field<ArCell> kFields[] = {
      {.key = "speed_mps",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(ArCell, speed_mps),
       .range = kSpeed,
       .unit = "m/s",
       .required = true,
       .doc = "scan speed of the condition"},
      {.key = "force_N",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(ArCell, force_N),
       .range = kForce,
       .unit = "N",
       .required = true,
       .doc = "normal force of the condition"},
      {.key = "ar",
       .type = Type::kNumbers,
       .ref = HL_FIELD_REF(ArCell, coeffs),
       .required = true,
       .doc = "AR coefficients c_1..c_p (order 1..64, a stable filter)"},
      {.key = "lsf",
       .type = Type::kCustom,
       .unit = "rad/sample",
       .doc = "the AR part's line spectral frequencies (checked against ar)",
       .default_text = "derived",
       .expected = "an array of finite numbers"},
      {.key = "variance",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(ArCell, variance),
       .range = {.lo = 0},
       .unit = "(m/s^2)^2",
       .required = true,
       .doc = "excitation variance"},
      {.key = "ma",
       .type = Type::kNumbers,
       .ref = HL_FIELD_REF(ArCell, ma),
       .doc = "MA coefficients b_1..b_q (minimum phase)",
       .default_text = "none (pure AR)"},
      {.key = "gain",
       .type = Type::kNumber,
       .ref = HL_FIELD_REF(ArCell, gain),
       .doc = "excitation gain"},
  };
  return kFields;
}

}  // namespace internal

std::string MaterialKeyTables() {
  using namespace internal;
  std::string s;
  auto section = [&s](const char* title, const std::string& table) {
    s += std::string("**") + title + "**\n\n" + table + "\n";
  };
  section("top level", fields::FieldsMarkdown(TopLevelFields()));
  section("[contact]", fields::FieldsMarkdown(ContactFields()));
  section("[friction]", fields::FieldsMarkdown(FrictionFields()));
  section("[geometry]", fields::FieldsMarkdown(GeometryFields()));
  section("[hybrid]", fields::FieldsMarkdown(HybridFields()));
  section("[vibration]", fields::FieldsMarkdown(VibrationFields()));
  section("[[vibration.cells]]", fields::FieldsMarkdown(CellFields()));
  section("[neural]", fields::FieldsMarkdown(NeuralFields()));
  s.pop_back();
  return s;
}

}  // namespace hapticlab::renderer
