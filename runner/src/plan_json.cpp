#include "hapticlab/runner/plan_json.hpp"

namespace hapticlab::runner {

nlohmann::json PlanToJson(const std::vector<protocols::PlannedTrial>& plan) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& t : plan)
    out.push_back({{"trial", t.index + 1},
                   {"plan_index", t.index},
                   {"phase", protocols::ToString(t.phase)},
                   {"material", t.material},
                   {"comparison", t.comparison},
                   {"method", t.method},
                   {"repetition", t.repetition},
                   {"left", t.left},
                   {"right", t.right},
                   {"rated", t.rated},
                   {"break_before", t.break_before}});
  return out;
}

}  // namespace hapticlab::runner
