#include "harness/record_types.hpp"

#include "harness/record_schema.hpp"
#include "solvers/core/types.hpp"

namespace cb {

namespace {

/// WHERE: how the record is named after SOURCE ("" when SOURCE is the record's own file).
void check_types(const nlohmann::json& run, const std::string& source, const std::string& where)
{
    auto refuse = [&](const std::string& field, const std::string& expected, const nlohmann::json& got) {
        throw_input_error(source, where + field, "expected " + expected + ", got " + got.dump());
    };
    auto optional = [&](const char* name, bool (nlohmann::json::*is)() const noexcept, const std::string& expected) {
        const auto it = run.find(name);
        if (it != run.end() && !((*it).*is)()) refuse(std::string("/") + name, expected, *it);
    };
    optional("status", &nlohmann::json::is_string, "a string");
    optional("label", &nlohmann::json::is_string, "a string");
    optional("solver", &nlohmann::json::is_string, "a string");
    optional("work_counted", &nlohmann::json::is_boolean, "true or false");
    optional("iterations", &nlohmann::json::is_number, "a number");
    optional("snapshot", &nlohmann::json::is_object, "an object");
    optional("counters", &nlohmann::json::is_object, "an object");
    optional("time", &nlohmann::json::is_object, "an object");
    if (const auto it = run.find("instructions"); it != run.end() && !it->is_null() && !it->is_number())
        refuse("/instructions", "a number or null", *it);
    if (const auto it = run.find("snapshot"); it != run.end())
        for (const char* name : {"id", "hash"})
            if (it->contains(name) && !(*it)[name].is_string())
                refuse(std::string("/snapshot/") + name, "a string", (*it)[name]);
    const bool counted = run.value("work_counted", true);
    if (const auto it = run.find("counters"); it != run.end())
        for (const auto& item : it->items())
            if (!item.value().is_number() && !(item.value().is_null() && !counted))
                refuse("/counters/" + item.key(), counted ? "a number" : "a number or null", item.value());
    if (const auto it = run.find("time"); it != run.end())
        for (const auto& item : it->items()) {
            if (item.key() != "samples_total_s") {
                if (!item.value().is_number()) refuse("/time/" + item.key(), "a number (seconds)", item.value());
                continue;
            }
            if (!item.value().is_array()) refuse("/time/samples_total_s", "an array of numbers", item.value());
            for (const auto& v : item.value())
                if (!v.is_number()) refuse("/time/samples_total_s", "numbers (seconds)", v);
        }
    const nlohmann::json& accuracy = accuracy_object(run, source);
    const std::string accuracy_name = run.contains("accuracy") ? "/accuracy" : "/kkt_relative";
    if (!accuracy.is_null() && !accuracy.is_object()) refuse(accuracy_name, "an object", accuracy);
    if (accuracy.is_object())
        for (const auto& item : accuracy.items())
            if (!item.value().is_number() && !item.value().is_null())
                refuse(accuracy_name + "/" + item.key(), "a number or null", item.value());
}

}  // namespace

void check_record_types(const nlohmann::json& run, const std::string& source)
{
    if (!run.is_object()) throw_input_error(source, "", "expected a run record (a JSON object), got " + run.dump());
    auto text = [](const nlohmann::json& object, const char* name) {  // before the types are known
        const auto it = object.is_object() ? object.find(name) : object.end();
        return it != object.end() && it->is_string() ? it->get<std::string>() : std::string("?");
    };
    // A folder's record by its file, a compact row by its key.
    check_types(run, source,
                run.contains("_file")
                    ? text(run, "_file") + ": "
                    : text(run.value("snapshot", nlohmann::json()), "id") + "/" + text(run, "label") + ": ");
}

void check_record_file_types(const nlohmann::json& run, const std::string& path)
{
    if (!run.is_object()) throw_input_error(path, "", "expected a run record (a JSON object), got " + run.dump());
    check_types(run, path, "");
}

}  // namespace cb
