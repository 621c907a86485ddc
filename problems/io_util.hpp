#pragma once
/// Safe file access shared by every reader and writer: inputs must be regular files (a FIFO, a
/// folder or a device is refused before anything blocks on it), JSON nesting is bounded before
/// the parser sees it, and outputs are written atomically (problems/safe_output.hpp: AtomicFile,
/// write_file_atomic). Errors are InputErrors naming the file ("PATH: problem"), so the command
/// line exits 2.
#include "problems/safe_output.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>

namespace cb {

/// Deepest JSON nesting any reader accepts (a header, suite, scene or settings file of ours
/// nests fewer than 10 levels; the parser and the destructor recurse once per level).
constexpr int MAX_JSON_DEPTH = 64;

/// Opens `path` read-only after checking (without blocking) that it is a regular file; returns
/// the descriptor. "cannot open: Too many levels of symbolic links", "not a regular file (a FIFO)".
int open_regular_file(const std::string& path);

/// "" when `path` is a regular file (links followed), else what it is, for messages that name
/// an input: "not found", "not a regular file (a FIFO)", "cannot open: Too many levels of
/// symbolic links". Never opens it.
std::string regular_file_problem(const std::string& path);

/// The same check for readers that open the file themselves (std::ifstream would block on a FIFO).
void require_regular_file(const std::string& path);

/// The whole of a regular file, refused when larger than `max_bytes`.
std::string read_regular_file(const std::string& path, std::uint64_t max_bytes = std::uint64_t(1) << 30);

/// Throws InputError("where: FIELD: nesting deeper than 64 levels at byte K") when brackets
/// outside strings nest deeper than `max_depth`; cheap (one pass, no allocation).
void check_json_depth(const char* begin, const char* end, const std::string& where, const std::string& field = "",
                      int max_depth = MAX_JSON_DEPTH);

/// Parses JSON text after the depth check; InputError("where: not valid JSON: ...") otherwise.
nlohmann::json parse_json_text(const std::string& text, const std::string& where, bool allow_comments = false);

/// read_regular_file + parse_json_text.
nlohmann::json read_json_checked(const std::string& path, bool allow_comments = false);

/// fsync of a folder, so that a rename inside it survives a crash (errors ignored: some file
/// systems refuse fsync on folders).
void fsync_dir(const std::string& dir);

/// Replaces folder `target` by folder `staged` (same parent) in one step where the kernel
/// allows (renameat2 RENAME_EXCHANGE), else by two renames that put the old folder back when
/// the second fails; the old content is removed afterwards. No "target.old.*" folder survives.
void replace_dir(const std::string& staged, const std::string& target);

}  // namespace cb
