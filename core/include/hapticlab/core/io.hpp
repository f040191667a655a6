#pragma once
/// @file Small file helpers shared by the readers of user input.

#include <string>

namespace hapticlab {

/// Whole file as text. @throws InputError naming the file ("cannot open <what>").
std::string ReadTextFile(const std::string& path, const std::string& what = "file");

}  // namespace hapticlab
