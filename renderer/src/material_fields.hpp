#pragma once
// The declared field tables of the material model file (core/fields.hpp): every key with its
// type, unit, physical range and meaning. material.cpp reads through them,
// material_validate.cpp checks models built in code against the same ranges, and
// MaterialKeyTables() prints them into docs/formats.md.

#include <span>

#include "hapticlab/core/fields.hpp"
#include "hapticlab/renderer/material.hpp"

namespace hapticlab::renderer::internal {

std::span<const fields::Field<MaterialModel>> TopLevelFields();
std::span<const fields::Field<ContactParams>> ContactFields();
std::span<const fields::Field<FrictionParams>> FrictionFields();
std::span<const fields::Field<MaterialModel>> GeometryFields();
std::span<const fields::Field<MaterialModel>> HybridFields();
std::span<const fields::Field<MaterialModel>> NeuralFields();
std::span<const fields::Field<VibrationBank>> VibrationFields();
std::span<const fields::Field<ArCell>> CellFields();

}  // namespace hapticlab::renderer::internal
