#pragma once
// Planned trial rows for the db tests, one Database::AddTrial each (the runner adds a session's
// plan the same way, inside its own transaction).

#include <cstdint>
#include <vector>

#include "hapticlab/db/database.hpp"

namespace hapticlab::db {

inline std::vector<std::int64_t> AddTrials(Database& d, const std::vector<Trial>& trials) {
  std::vector<std::int64_t> ids;
  for (const auto& t : trials) ids.push_back(d.AddTrial(t));
  return ids;
}

}  // namespace hapticlab::db
