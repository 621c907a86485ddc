#pragma once
/// The rule for what a command writes or deletes inside an output folder (issue 40): the folder
/// named on the command line is created when missing (it may itself be a link the user made:
/// the user pointed there), but no entry inside it that the command writes or deletes, a
/// sub-folder such as runs/ included, may be a symbolic link or a special file (FIFO, device,
/// socket). Such an entry is refused with an InputError naming it (exit status 2), before
/// anything is written or deleted, so a link planted in a results folder never leads a write or
/// a delete elsewhere. (Writes themselves go through AtomicFile, problems/safe_output.hpp.)
#include <functional>
#include <string>

namespace cb {

/// InputError "PATH: is a symbolic link: ..." or "PATH: is a FIFO ..." when PATH exists and is a
/// link or a special file; also when `folder` is true and PATH is a regular file, or false and
/// PATH is a folder. A missing PATH passes.
void check_output_entry(const std::string& path, bool folder = false);

/// Creates `folder` (and its parents) when missing; InputError naming it when it cannot be made
/// or is not a folder (a link to a folder is accepted: this is the folder the user named).
void make_output_folder(const std::string& folder);

/// FOLDER/NAME as a real sub-folder: FOLDER made as by make_output_folder, FOLDER/NAME created
/// when missing and refused when it is a link or not a folder (check_output_entry). Returns its path.
std::string make_output_subfolder(const std::string& folder, const std::string& name);

/// check_output_entry on every entry of `folder` (not recursive) whose name `select` accepts; a
/// missing folder passes.
void check_output_entries(const std::string& folder, const std::function<bool(const std::string&)>& select);

}  // namespace cb
