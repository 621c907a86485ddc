#pragma once
/// Settings given as text on the command line: `contactbench solve --set key=value` and the
/// stress solver specs `NAME:key=value[:key=value...]`. One rule for a value's type, so that a
/// setting means the same wherever it is typed: true/false are booleans, an integer is an integer,
/// another number is a double, anything else is a string (the solver's reader then checks it).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cb {

/// The JSON value of one setting typed as text.
nlohmann::json setting_from_text(const std::string& text);

/// "key=value" strings (repeated --set) as a settings object; InputError("--set: ITEM: expected
/// key=value") on an item without '=' or without a key.
nlohmann::json settings_from_assignments(const std::vector<std::string>& assignments);

}  // namespace cb
