#include "harness/record_schema.hpp"

#include <iostream>
#include <mutex>
#include <set>
#include <utility>

namespace cb {

namespace {

// Once per (file, old name): a results folder of old run files would otherwise repeat it per run.
void notice_old_name(const std::string& source, const std::string& old_name, const std::string& new_name)
{
    static std::mutex mutex;
    static std::set<std::pair<std::string, std::string>> told;
    const std::lock_guard<std::mutex> lock(mutex);
    if (!told.insert({source, old_name}).second) return;
    std::cerr << "notice: " << source << ": read the old name '" << old_name << "' as '" << new_name
              << "' (accepted until the next release; rewrite the file to use '" << new_name << "')\n";
}

}  // namespace

std::string current_column_name(const std::string& column, const std::string& source)
{
    static const std::pair<const char*, const char*> renamed[] = {{"kkt_rel", "accuracy"},
                                                                  {"kkt_rel_solved", "accuracy_solved"}};
    for (const auto& [old_name, new_name] : renamed)
        if (column == old_name) {
            notice_old_name(source, old_name, new_name);
            return new_name;
        }
    return column;
}

const nlohmann::json& accuracy_object(const nlohmann::json& run, const std::string& source)
{
    static const nlohmann::json none;
    if (!run.is_object()) return none;
    if (const auto it = run.find("accuracy"); it != run.end()) return *it;
    if (const auto it = run.find("kkt_relative"); it != run.end()) {
        notice_old_name(source, "kkt_relative", "accuracy");
        return *it;
    }
    return none;
}

nlohmann::json accuracy_max(const nlohmann::json& run, const std::string& source)
{
    const nlohmann::json& accuracy = accuracy_object(run, source);
    if (accuracy.is_object() && accuracy.contains("max")) return accuracy["max"];
    return nullptr;
}

}  // namespace cb
