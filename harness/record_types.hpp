#pragma once
/// The types of a run record's fields, checked before any reader uses them.
#include <nlohmann/json.hpp>
#include <string>

namespace cb {

/// Refuses (InputError naming SOURCE and the JSON pointer) a record whose fields that compare,
/// merge and the plots read have the wrong type: a string counter would otherwise be skipped as
/// "not recorded" and a wrong type end in a raw nlohmann type_error. Absent fields stay allowed
/// (older records); null only where it means "not counted" (work_counted false) or "not computed"
/// (accuracy).
void check_record_types(const nlohmann::json& run, const std::string& source);

/// The same for a record read from its own file PATH (the error names PATH and the field only).
void check_record_file_types(const nlohmann::json& run, const std::string& path);

}  // namespace cb
