// A layout check (layout_check.hpp) as JSON: what `axon fps layout check --json` and `fps plane check
// --json` print and what the actor's `check` keyword `layout_check` carries (docs/schema/fps.json).
#pragma once

#include "axon/fps/layout/layout_check.hpp"

#include <nlohmann/json.hpp>

namespace axon::fps {

// {ok, matched, missing, offline_answered, offline_silent, not_checked, wrong_bus: [{id, expected,
// found}], unexpected: [{id, found}], duplicated: [{id, found}], failed_buses: {bus: why}}
nlohmann::json to_json(const LayoutCheck& check);

}  // namespace axon::fps
