#pragma once
/// Text from an external program (its stderr, the message of its result.json) made safe to print
/// on a terminal and to store in a JSON record (issue 40, C9): terminal escape sequences (ESC
/// followed by a CSI, OSC, DCS... sequence or one character) are removed, other control
/// characters but newline and tab become a space (a carriage return could overwrite a line, a
/// BEL rings), and bytes that are not valid UTF-8, or encode a C1 control, become '?'.
#include <string>

namespace cb {

std::string printable_text(const std::string& raw);

}  // namespace cb
