// The registry of export formats (db/export_formats.hpp).

#include "hapticlab/db/export_formats.hpp"

#include <stdexcept>

namespace hapticlab::db {
namespace {

std::vector<ExportFormat>& Registry() {
  // One line per built-in format.
  static std::vector<ExportFormat> formats{
      CsvExportFormat(),
      BidsExportFormat(),
      XdfExportFormat(),
  };
  return formats;
}

}  // namespace

const std::vector<ExportFormat>& ExportFormats() { return Registry(); }

const ExportFormat* FindExportFormat(const std::string& name) {
  for (const auto& f : Registry())
    if (f.name == name) return &f;
  return nullptr;
}

void RegisterExportFormat(ExportFormat format) {
  if (FindExportFormat(format.name))
    throw std::logic_error("export format '" + format.name + "' is registered twice");
  Registry().push_back(std::move(format));
}

}  // namespace hapticlab::db
