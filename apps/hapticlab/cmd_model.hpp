#pragma once
// The `model` command group's subcommands, one file per family (private to the CLI).

#include <CLI/CLI.hpp>
#include <string>

namespace hapticlab::cli {

// cmd_model_vibration.cpp
void AddFitVibration(CLI::App& model);
void AddFitNeural(CLI::App& model);
void AddCvVibration(CLI::App& model);
void AddCutoff(CLI::App& model);
// cmd_model_score.cpp
void AddScore(CLI::App& model);
void AddIdentify(CLI::App& model);
// cmd_model_contact.cpp
void AddFitContact(CLI::App& model);
// cmd_model_photometric.cpp
void AddPhotometric(CLI::App& model);

}  // namespace hapticlab::cli
